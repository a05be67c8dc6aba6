#!/bin/sh
# OBJ text writer of `roadsplat mesh` (cli/numfmt.c; docs/roam.md "CLI
# conventions"): its numbers against printf's on the same values in one
# process (build/tools/numfmt_check --bench), and the write stage of an OBJ
# against the PLY of the same mesh (the 1025^2 fractal at 0.05 m, with
# normals; `timings_ms.write`, fastest of RUNS each, interleaved).
# Writes <outdir>/obj.md and obj.csv.
set -e
OUT=${1:?usage: obj.sh OUTDIR}
B=${BUILD:-build}
BIN=$B/roadsplat
RUNS=${OBJ_BENCH_RUNS:-3}
mkdir -p "$OUT"
MD="$OUT/obj.md"; CSV="$OUT/obj.csv"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/lib.sh" # fastest, field

nf=$("$B/tools/numfmt_check" --bench)
count=$(echo "$nf" | sed -n 's/^numbers \([0-9]*\),.*/\1/p')
ns_fast=$(echo "$nf" | sed -n 's/.*cli_fmt_g \([0-9.]*\) ns.*/\1/p')
ns_printf=$(echo "$nf" | sed -n 's/.*printf \([0-9.]*\) ns.*/\1/p')
ratio=$(echo "$nf" | sed -n 's/.*ratio \([0-9.]*\),.*/\1/p')
same=$(echo "$nf" | sed -n 's/.*same bytes \([a-z]*\).*/\1/p')

"$B/tools/demgen" 1025 "$T/dem.pgm"
for r in $(seq "$RUNS"); do
    for f in obj ply; do
        "$BIN" mesh -q --normals --max-error 0.05 --stats "$T/$f$r.json" "$T/dem.pgm" "$T/m.$f"
    done
done
w_obj=$(for r in $(seq "$RUNS"); do field write "$T/obj$r.json"; done | fastest)
w_ply=$(for r in $(seq "$RUNS"); do field write "$T/ply$r.json"; done | fastest)
t_obj=$(for r in $(seq "$RUNS"); do field total "$T/obj$r.json"; done | fastest)
tris=$(sed -n 's/.*"triangles": \([0-9]*\).*/\1/p' "$T/obj1.json" | head -n 1)
s_obj=$(wc -c < "$T/m.obj"); s_ply=$(wc -c < "$T/m.ply")

echo "what,value" > "$CSV"
echo "numbers,$count" >> "$CSV"
echo "ns_cli_fmt_g,$ns_fast" >> "$CSV"
echo "ns_printf,$ns_printf" >> "$CSV"
echo "obj_write_ms,$w_obj" >> "$CSV"
echo "ply_write_ms,$w_ply" >> "$CSV"
{
    echo "## OBJ writer (tests/bench/obj.sh)"
    echo
    echo "\`roadsplat mesh\` writes an OBJ's numbers with cli/numfmt.c, which gives printf's \`%.9g\` / \`%.10g\` /"
    echo "\`%.7g\` text (docs/roam.md \"CLI conventions\"). The same $count numbers of the kinds an OBJ holds"
    echo "(coordinates, heights, texture coordinates, normals), formatted both ways in one process, fastest"
    echo "of 5 each, interleaved (process CPU time); then the 1025^2 fractal meshed at 0.05 m with normals"
    echo "($tris triangles) to OBJ and to PLY, \`timings_ms.write\` (the file's write, fsync and rename"
    echo "included), fastest of $RUNS each, interleaved."
    echo
    echo "| | ns per number | same bytes |"
    echo "|---|---|---|"
    echo "| cli_fmt_g | $ns_fast | $same |"
    echo "| snprintf (glibc) | $ns_printf | |"
    echo "| ratio | **${ratio}x** faster | |"
    echo
    echo "| file | MB | write ms |"
    echo "|---|---|---|"
    echo "| OBJ (text) | $(awk -v b="$s_obj" 'BEGIN { printf "%.1f", b / 1e6 }') | $w_obj (whole run $t_obj) |"
    echo "| PLY (binary) | $(awk -v b="$s_ply" 'BEGIN { printf "%.1f", b / 1e6 }') | $w_ply |"
} > "$MD"
[ "$same" = yes ] || { echo "obj.sh: cli_fmt_g and printf wrote different bytes" >&2; exit 1; }
