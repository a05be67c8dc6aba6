#!/bin/sh
# CLI tests for `roadsplat render --path` (the flythrough through the
# virtual texture, cli/render_vt.c). Usage: sh tests/cli_vt_test.sh ROADSPLAT
# Prints "N passed, N failed"; skips without OSMesa or python3.
BIN=${1:?usage: cli_vt_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
if [ -n "${SAN:-}" ]; then LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}use_tls=0"; export LSAN_OPTIONS; fi
if "$BIN" render --help 2>&1 | grep -q "no OSMesa support"; then
    echo "SKIP cli_vt: $BIN was built without OSMesa"; echo "cli_vt: 0 passed, 0 failed"; exit 0
fi
if ! command -v python3 >/dev/null 2>&1; then
    echo "SKIP cli_vt: python3 is needed to read the PNGs"; echo "cli_vt: 0 passed, 0 failed"; exit 0
fi
EX=$(dirname "$0")/../docs/examples
cat > "$T/mad.py" <<'PY'
import json, sys
sys.path.insert(0, sys.argv[1])
from png_read import read
if sys.argv[2] == 'mad':  # a b limit: mean absolute RGB difference <= limit/255
    (w, h, c, a), (w2, h2, c2, b) = read(sys.argv[3]), read(sys.argv[4])
    if (w, h) != (w2, h2): print('sizes differ'); sys.exit(1)
    s = sum(abs(a[i * c + k] - b[i * c + k]) for i in range(w * h) for k in range(3)) / (3.0 * w * h)
    print('mean abs diff %.4f / 255' % s); sys.exit(0 if s <= float(sys.argv[5]) else 1)
if sys.argv[2] == 'stats':  # the stats keys and their sense
    s = json.load(open(sys.argv[3])); n = int(sys.argv[4])
    ok = s['frames'] == n and len(s['per_frame']['texture_ms']) == n and len(s['per_frame']['tiles_made']) == n
    ok = ok and s['texture_ms']['p50'] <= s['texture_ms']['p99'] <= s['texture_ms']['max']
    ok = ok and s['frame_ms']['p99'] <= s['frame_ms']['max'] and s['tiles_made']['max'] >= 1
    ok = ok and 0 < s['resident_mb_max'] <= s['virtual_texture']['budget_bytes'] / 1048576.0
    print(s['texture_ms'], s['tiles_made'], s['resident_mb_max']); sys.exit(0 if ok else 1)
PY
py() { python3 "$T/mad.py" "$(dirname "$0")" "$@" >"$T/py.out" 2>&1 || { cat "$T/py.out"; return 1; }; sed "s/^/     /" "$T/py.out"; }
S="--cell-size 5 --z-scale 0.01 --texels 16"
printf '# eye X Y Z  look-at X Y Z\n100 500 120  400 300 0\n\n500 450 80  300 100 0 # last\n' > "$T/path.txt"
check "render --path exits 0" "$BIN" render $S --quiet --path "$T/path.txt" --frames 12 --size 320x180 --fov 45 \
    --stats "$T/s.json" "$EX/dem.pgm" "$EX/roads.txt" "$T/fly.png"
check "stats: frames, percentiles, tiles made, resident within the budget" py stats "$T/s.json" 12
# the last frame against the baked texture's render of the same view (isotropic filtering)
check "baked render of the last view" "$BIN" render $S --quiet --roads texture --anisotropy 1 --camera 500,450,80 \
    --look-at 300,100,0 --fov 45 --size 320x180 "$EX/dem.pgm" "$EX/roads.txt" "$T/baked.png"
check "the flythrough's last frame equals the baked render (MAD <= 1/255)" py mad "$T/fly.png" "$T/baked.png" 1
# a tight budget and a cap on the tiles made a frame still render
check "render --path --budget-mb 2 --max-make 1" "$BIN" render $S --quiet --path "$T/path.txt" --frames 6 \
    --size 160x90 --budget-mb 2 --max-make 1 "$EX/dem.pgm" "$EX/roads.txt" "$T/tight.png"
# bad input: one clear line naming file and line, exit 1, no output
fails() { # description, expected message part, path text
    printf "$3" > "$T/bad.txt"
    rm -f "$T/bad.png"
    if "$BIN" render $S --quiet --path "$T/bad.txt" --frames 2 --size 32x32 "$EX/dem.pgm" "$EX/roads.txt" "$T/bad.png" \
        2>"$T/err"; then bad "$1: exit 0"; return; fi
    if [ -e "$T/bad.png" ]; then bad "$1: output written"; return; fi
    if [ "$(wc -l < "$T/err")" -ne 1 ] || ! grep -q "$2" "$T/err"; then bad "$1: message: $(cat "$T/err")"; return; fi
    ok
}
fails "a word in the path" "bad.txt line 2: 'x' is not a number" '1 2 3 4 5 6\n1 2 x 4 5 6\n'
fails "five numbers" "bad.txt line 1: 5 numbers, need 6" '1 2 3 4 5\n1 2 3 4 5 6\n'
fails "one key frame" "bad.txt: 1 key frames, need at least 2" '1 2 3 4 5 6\n'
fails "eye on the target" "bad.txt line 2: the eye is the point looked at" '1 2 3 4 5 6\n1 2 3 1 2 3\n'
fails "huge coordinate" "beyond 1e9" '1 2 3 4 5 6\n1e12 2 3 4 5 6\n'
if "$BIN" render $S --quiet --path "$T/none.txt" "$EX/dem.pgm" "$EX/roads.txt" "$T/bad.png" 2>"$T/err"; then
    bad "missing path file: exit 0"
elif grep -q "none.txt" "$T/err"; then ok; else bad "missing path file: $(cat "$T/err")"; fi
if "$BIN" render $S --quiet --path "$T/path.txt" --frames 0 "$EX/dem.pgm" "$EX/roads.txt" "$T/bad.png" 2>"$T/err"; then
    bad "--frames 0: exit 0"
elif grep -q "frames" "$T/err"; then ok; else bad "--frames 0: $(cat "$T/err")"; fi
echo "cli_vt: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
