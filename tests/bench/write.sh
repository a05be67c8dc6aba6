#!/bin/sh
# PNG output and start-up benchmark (`make bench` runs it; issue 18). In one run:
# - `roadsplat` on a 1025^2 fractal DEM at 4 texels (4096^2 pixels, written as RGB: 48 MB raw, one
#   road), with --threads 1 and with the default thread count, the runs
#   interleaved: stages from --stats, fastest of RUNS each;
# - the same texture written by cli/png.c at several --png-level values and by
#   OpenImageIO 2.4's PNG writer (libpng, zlib level 6, adaptive filters: what
#   the CLI used before), sizes as ratios to the latter;
# - `roadsplat --version` wall time, and the shared libraries a `roadsplat
#   mesh` of a PGM and a splat of a PNG DEM load (LD_DEBUG=libs).
# Writes <outdir>/write.md and write.csv. Needs build/tests/test_png and
# build/tools/demgen (`make bench` builds them).
set -e
OUT=${1:?usage: write.sh OUTDIR}
B=${BUILD:-build}
BIN=$B/roadsplat
PNGT=$B/tests/test_png
RUNS=${WRITE_BENCH_RUNS:-5}
mkdir -p "$OUT"
MD="$OUT/write.md"; CSV="$OUT/write.csv"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT

. "$(dirname "$0")/lib.sh" # fastest, field
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }

"$B/tools/demgen" 1025 "$T/dem.pgm"
printf 'road main width 6\n300 300\n700 450\n900 980\nend\n' > "$T/roads.txt"
ncpu=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?')

# 1. The CLI at the default level: one thread and the default (all cores),
#    interleaved so both see the same machine.
for r in $(seq "$RUNS"); do
    "$BIN" --quiet --threads 1 --texels 4 --z-scale 0.01 --stats "$T/s$r.json" "$T/dem.pgm" "$T/roads.txt" "$T/out1.png"
    "$BIN" --quiet --texels 4 --z-scale 0.01 --stats "$T/d$r.json" "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
done
for k in startup read roads splat write total png_cpu splat_cpu wall; do
    eval "t_$k=\$(for r in \$(seq $RUNS); do field $k \"\$T/s\$r.json\"; done | fastest)"
    eval "d_$k=\$(for r in \$(seq $RUNS); do field $k \"\$T/d\$r.json\"; done | fastest)"
done
d_threads=$(field threads "$T/d1.json")
size_cli=$(wc -c < "$T/out.png")
same_threads=$(cmp -s "$T/out.png" "$T/out1.png" && echo yes || echo '**no**')
joins=$(sed -n 's/.*"png_pieces_joined": {\(.*\)}.*/\1/p' "$T/d1.json" | tr -d '"')

# 2. Writers on the same pixels.
oiio=$("$PNGT" --time-oiio "$T/out.png" "$T/oiio.png" 1) # ~10x slower: one run
oiio_ms=${oiio% *}; oiio_bytes=${oiio#* }
echo "writer,level,ms,bytes" > "$CSV"
echo "oiio,6,$oiio_ms,$oiio_bytes" >> "$CSV"
rows=""
for L in 0 1 2 3 4 6; do # 9 takes ~25x longer than 1; 10-12 longer still
    n=1; [ "$L" = 1 ] && n=$RUNS
    res=$("$PNGT" --time-level "$L" "$T/out.png" "$T/l.png" "$n")
    ms=${res% *}; bytes=${res#* }
    [ "$L" = 1 ] && same_encode=$(cmp -s "$T/out.png" "$T/l.png" && echo yes || echo '**no**')
    echo "png.c,$L,$ms,$bytes" >> "$CSV"
    rows="$rows| cli/png.c level $L$( [ "$L" = 1 ] && echo ' (default)') | $ms | $(ratio "$ms" "$t_splat") | $(awk -v b="$bytes" 'BEGIN { printf "%.1f", b / 1048576 }') | $(ratio "$bytes" "$oiio_bytes") |
"
done

# 3. Start-up and loaded libraries.
if command -v hyperfine >/dev/null 2>&1; then
    hyperfine -N --warmup 5 --runs 100 --export-json "$T/hf.json" "$BIN --version" >/dev/null 2>&1
    ver_ms=$(awk '/"mean"/ { gsub(/[",]/, "", $2); printf "%.2f", $2 * 1000; exit }' "$T/hf.json")
    how="hyperfine, mean of 100 runs"
else
    t0=$(date +%s%N); for i in $(seq 50); do "$BIN" --version >/dev/null; done; t1=$(date +%s%N)
    ver_ms=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", (b - a) / 50 / 1e6 }')
    how="shell loop, mean of 50 runs"
fi
t0=$(date +%s%N); for i in $(seq 50); do /bin/true; done; t1=$(date +%s%N)
true_ms=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", (b - a) / 50 / 1e6 }')
# LD_DEBUG_OUTPUT: the CLI sends fd 2 elsewhere while OpenImageIO reads.
ldlog() { rm -f "$T"/ld.*; LD_DEBUG=libs LD_DEBUG_OUTPUT="$T/ld" "$@" >/dev/null 2>&1; cat "$T"/ld.*; }
libs() { ldlog "$@" | grep -c 'calling init:' || true; }
has() { ldlog "$@" | grep 'calling init:' | grep -c "$LIB" || true; }
lib_ver=$(libs "$BIN" --version)
lib_mesh=$(libs "$BIN" mesh docs/examples/dem.pgm "$T/m.obj")
LIB=OpenImageIO; oiio_mesh=$(has "$BIN" mesh docs/examples/dem.pgm "$T/m.obj")
LIB=OSMesa; osm_mesh=$(has "$BIN" mesh docs/examples/dem.pgm "$T/m.obj")
"$BIN" --quiet --texels 1 docs/examples/dem.pgm docs/examples/roads.txt "$T/small.png"
lib_png=$(libs "$BIN" --quiet --texels 1 "$T/small.png" docs/examples/roads.txt "$T/small2.png")

verdict() { awk -v a="$1" -v b="$2" 'BEGIN { print (a <= b) ? "met" : "**missed**" }'; }
{
echo "## PNG output and start-up (tests/bench/write.sh)"
echo
echo "\`roadsplat --texels 4 --z-scale 0.01\` on a 1025x1025 fractal DEM (tests/tools/demgen.c) with one"
echo "road: a 4096x4096 texture (written as RGB, 48 MiB raw: every pixel is opaque; docs/packaging.md), run $RUNS times with \`--threads 1\` and $RUNS times with the"
echo "default thread count ($d_threads threads, $ncpu cores), interleaved; every time is the fastest of its $RUNS"
echo "from \`--stats\`. The splat and the PNG run together, band by band (docs/packaging.md): \`splat\` is the"
echo "splat's time per thread (its CPU time summed over the threads, divided by them; with one thread"
echo "exactly its time), \`write\` the rest of their wall time (compression not hidden behind the splat,"
echo "writing, fsync, completeness check), \`png cpu\` the filtering and compression summed over threads."
echo "Both runs write the same bytes: $same_threads. Pieces joined (default run): $joins."
echo
echo "| stage, ms (fastest of $RUNS) | \`--threads 1\` | default ($d_threads threads) |"
echo "|---|---|---|"
echo "| start-up (\`timings_ms.startup\`) | $t_startup | $d_startup |"
echo "| read | $t_read | $d_read |"
echo "| roads | $t_roads | $d_roads |"
echo "| splat | $t_splat | $d_splat |"
echo "| write (default level 1, $(awk -v b="$size_cli" 'BEGIN { printf "%.1f", b / 1048576 }') MiB) | $t_write | $d_write |"
echo "| (png cpu) | $t_png_cpu | $d_png_cpu |"
echo "| total | $t_total | $d_total |"
echo
echo "Where the default run's total goes (fastest runs): read + roads $(awk -v a="$d_read" -v b="$d_roads" 'BEGIN { printf "%.0f", a + b }') ms, one thread each;"
echo "the splat and the PNG together $(printf '%.0f' "$d_wall") ms of wall time for $(printf '%.0f' "$d_splat_cpu") + $(printf '%.0f' "$d_png_cpu") ms of splat + PNG CPU time"
echo "(one thread: $(printf '%.0f' "$t_splat_cpu") + $(printf '%.0f' "$t_png_cpu") ms); the rest (flush, fsync beside the completeness check, close) about"
echo "$(awk -v t="$d_total" -v a="$d_read" -v b="$d_roads" -v w="$d_wall" 'BEGIN { v = t - a - b - w; printf "%.0f", v < 0 ? 0 : v }') ms."
echo
echo "The writers then write the same pixels again in one thread (tests/png/test_png.cpp, the in-memory"
echo "encoder cli_png_encode, which writes the same bytes as the CLI: $same_encode; the default level $RUNS"
echo "times, the others once; timings include the temporary file, fsync, completeness check and rename,"
echo "as in the CLI). The reference is OpenImageIO 2.4's PNG writer (libpng, zlib's default level 6,"
echo "adaptive filters), which the CLI used before (one run). The ratio column divides by the 1-thread"
echo "splat stage."
echo
echo "| writer | write ms | / splat stage | MiB | size / OpenImageIO |"
echo "|---|---|---|---|---|"
echo "| OpenImageIO 2.4 + libpng (level 6, adaptive) | $oiio_ms | $(ratio "$oiio_ms" "$t_splat") | $(awk -v b="$oiio_bytes" 'BEGIN { printf "%.1f", b / 1048576 }') | 1.00 |"
printf '%s' "$rows"
echo
echo "Start-up: \`roadsplat --version\` takes $ver_ms ms ($how; \`/bin/true\` takes $true_ms ms"
echo "in a shell loop on this machine). Shared objects initialised (LD_DEBUG=libs):"
echo "\`--version\` $lib_ver, \`mesh\` of a PGM $lib_mesh (OpenImageIO: $oiio_mesh, OSMesa: $osm_mesh), a splat with a PNG"
echo "DEM (loads roadsplat-image.so) $lib_png."
echo
echo "| target (issue 18) | measured | |"
echo "|---|---|---|"
echo "| write stage (default threads) <= 1-thread splat stage | $(ratio "$d_write" "$t_splat")x | $(verdict "$d_write" "$t_splat") |"
echo "| (write stage with \`--threads 1\` / 1-thread splat stage) | $(ratio "$t_write" "$t_splat")x | |"
echo "| PNG size <= 1.5x zlib's default level | $(ratio "$size_cli" "$oiio_bytes")x | $(verdict "$(ratio "$size_cli" "$oiio_bytes")" 1.5) |"
echo "| total (default threads) <= 1.5x 1-thread splat stage | $(ratio "$d_total" "$t_splat")x | $(verdict "$(ratio "$d_total" "$t_splat")" 1.5) |"
echo "| write speed-up over OpenImageIO (default threads) | $(ratio "$oiio_ms" "$d_write")x | |"
echo "| \`roadsplat --version\` <= 20 ms | $ver_ms ms | $(verdict "$ver_ms" 20) |"
echo "| \`mesh\` of a PGM loads neither OpenImageIO nor OSMesa | $oiio_mesh + $osm_mesh | $(verdict "$((oiio_mesh + osm_mesh))" 0) |"
} > "$MD"
echo "write bench: wrote $MD"
