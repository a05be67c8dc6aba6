#!/bin/sh
# `roadsplat mesh OUT.glb` (issue 32, docs/gltf.md): binary glTF 2.0 that a
# validator accepts, with the OBJ path's vertices, triangles and error.
# Usage: sh tests/cli_gltf_test.sh PATH/TO/roadsplat. Prints "N passed, N
# failed"; without the glTF module (no libmeshoptimizer-dev) one SKIP line.
BIN=${1:?usage: cli_gltf_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
B=$(dirname "$BIN")
CHECK=$(dirname "$0")/gltf_check.py
E=docs/examples
if [ ! -f "$B/roadsplat-gltf.so" ]; then
    echo "SKIP cli_gltf: $B/roadsplat-gltf.so not built (install libmeshoptimizer-dev, or run 'make deps', and rebuild)"
    echo "cli_gltf: 0 passed, 0 failed"
    exit 0
fi
M="--cell-size 5 --z-scale 0.01"
"$BIN" --quiet $M --texels 2 "$E/dem.pgm" "$E/roads.txt" "$T/tex.png" || bad "texture render"

# the same mesh three ways: OBJ, GLB, GLB with the texture embedded
for err in 0.5 0; do
    "$BIN" mesh $M --max-error $err --normals --stats "$T/o.json" "$E/dem.pgm" "$T/m.obj" &&
        "$BIN" mesh $M --max-error $err --texture "$T/tex.png" --stats "$T/g.json" "$E/dem.pgm" "$T/m.glb" &&
        ok || bad "mesh --max-error $err to OBJ and GLB"
    python3 "$CHECK" "$T/m.glb" "$T/m.obj" "$T/tex.png" >"$T/c.txt" && ok ||
        bad "max error $err: GLB structure or content: $(cat "$T/c.txt")"
    for k in vertices triangles max_error_measured max_error_bound; do
        a=$(sed -n "s/^  \"$k\": \([^,]*\),\$/\1/p" "$T/o.json")
        b=$(sed -n "s/^  \"$k\": \([^,]*\),\$/\1/p" "$T/g.json")
        [ -n "$a" ] && [ "$a" = "$b" ] && ok || bad "max error $err: $k OBJ '$a' GLB '$b'"
    done
    # the GLB's own counts, and a vertex cache no worse than the mesher's order
    python3 -c "import json,sys; g = json.load(open(sys.argv[1]))['glb']; sys.exit(not g['acmr_after'] <= g['acmr_before'])" \
        "$T/g.json" && ok || bad "acmr after > before: $(grep glb "$T/g.json")"
done

# a triangle budget, a skirt, no texture; deterministic bytes
"$BIN" mesh $M --triangles 2000 --skirt 20 --normals "$E/dem.pgm" "$T/s.obj" &&
    "$BIN" mesh $M --triangles 2000 --skirt 20 "$E/dem.pgm" "$T/s.glb" &&
    python3 "$CHECK" "$T/s.glb" "$T/s.obj" >"$T/c.txt" && ok || bad "skirt GLB: $(cat "$T/c.txt")"
"$BIN" mesh $M --triangles 2000 --skirt 20 "$E/dem.pgm" "$T/s2.glb" && cmp -s "$T/s.glb" "$T/s2.glb" && ok ||
    bad "GLB bytes differ between runs"

# more than 65535 vertices: 32-bit indices
awk 'BEGIN { W = 300; H = 260; print "P2"; print W, H; print 65535;
  for (i = 0; i < H; i++) { line = "";
    for (j = 0; j < W; j++) line = line " " int(30000 + 9000 * sin(j * 0.37) * cos(i * 0.29) + 7 * ((i * 131 + j * 71) % 97));
    print line } }' >"$T/big.pgm"
"$BIN" mesh --z-scale 0.01 --max-error 0 --normals "$T/big.pgm" "$T/big.obj" && "$BIN" mesh --z-scale 0.01 --max-error 0 "$T/big.pgm" "$T/big.glb" &&
    python3 "$CHECK" "$T/big.glb" "$T/big.obj" >"$T/c.txt" && grep -q '"componentType":5125,"count":[0-9]*,"type":"SCALAR"' "$T/big.glb" &&
    ok || bad "large GLB (32-bit indices): $(cat "$T/c.txt")"

# the Khronos glTF validator (npm gltf-validator), installed once into the
# build folder when npm reaches its registry
V=$B/gltf-validator
if [ ! -f "$V/node_modules/gltf-validator/package.json" ] && command -v npm >/dev/null 2>&1; then
    mkdir -p "$V" && (cd "$V" && timeout 120 npm install --no-audit --no-fund --silent gltf-validator@2.0.0-dev.3.10 >/dev/null 2>&1)
fi
if command -v node >/dev/null 2>&1 && [ -f "$V/node_modules/gltf-validator/package.json" ]; then
    cat >"$T/validate.js" <<'JS'
const v = require(process.argv[2] + '/node_modules/gltf-validator');
const data = new Uint8Array(require('fs').readFileSync(process.argv[3]));
v.validateBytes(data, { maxIssues: 50 }).then(r => {
  const e = r.issues.numErrors, w = r.issues.numWarnings;
  if (e || w) console.log(JSON.stringify(r.issues.messages));
  process.exit(e || w ? 1 : 0);
}).catch(err => { console.log(String(err)); process.exit(2); });
JS
    for g in m.glb s.glb big.glb; do
        node "$T/validate.js" "$(cd "$V" && pwd)" "$T/$g" >"$T/v.txt" 2>&1 && ok || bad "gltf-validator $g: $(head -c 600 "$T/v.txt")"
    done
else
    echo "SKIP cli_gltf: the Khronos validator (npm gltf-validator) could not be installed; the structure check above still ran"
fi

# errors: one line, exit 1, nothing written or replaced
printf 'P2\n2 2\n1\n0 1\n1 0\n' >"$T/notimg.pgm"
"$BIN" mesh $M --texture "$T/notimg.pgm" "$E/dem.pgm" "$T/x.glb" 2>"$T/e" && bad "a PGM texture was embedded" ||
    { grep -q "neither PNG nor JPEG" "$T/e" && [ ! -e "$T/x.glb" ] && ok || bad "PGM texture: $(cat "$T/e")"; }
cp "$T/m.glb" "$T/keep.glb"
"$BIN" mesh $M --texture "$T/keep.glb" "$E/dem.pgm" "$T/keep.glb" 2>"$T/e" && bad "texture == OUT accepted" ||
    { grep -q "refusing to overwrite an input" "$T/e" && cmp -s "$T/m.glb" "$T/keep.glb" && ok || bad "texture == OUT: $(cat "$T/e")"; }
"$BIN" mesh $M "$E/dem.pgm" "$T/m.gltf" 2>"$T/e" && bad ".gltf accepted" ||
    { grep -q "must end in .obj, .ply or .glb" "$T/e" && ok || bad ".gltf: $(cat "$T/e")"; }

echo "cli_gltf: $pass passed, $fail failed"
[ "$fail" = 0 ]
