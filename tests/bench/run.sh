#!/bin/sh
# `make bench`: runs every benchmark binary (build/bench/*) and script
# (tests/bench/*.sh but lib.sh, their helpers). Each writes a Markdown
# section to build/bench/<name>.md and CSV next to it; the gnuplot scripts
# tests/bench/*.gp turn the CSV into docs/bench/*.png; this script joins the
# sections into docs/BENCHMARKS.md with the machine and the command.
# BENCH_ONLY="tests/bench/x.sh ...": run only those scripts, keep the other
# sections of the last full run, and join them again.
set -e
B=${BUILD:-build}
mkdir -p "$B/bench" docs/bench
[ -n "${BENCH_ONLY:-}" ] || rm -f "$B"/bench/*.md
for b in "$B"/bench/*; do
    [ -z "${BENCH_ONLY:-}" ] || break
    case "$b" in *.md|*.csv|*.json|*.txt|*.png|*.gp|*.f32|*.bin) continue;; esac
    [ -x "$b" ] && [ -f "$b" ] || continue
    echo "bench: $(basename "$b")"
    "$b" "$B/bench" || { echo "bench: $(basename "$b") failed"; exit 1; }
done
for s in ${BENCH_ONLY:-tests/bench/*.sh}; do
    case "$s" in tests/bench/run.sh|tests/bench/lib.sh) continue ;; esac
    [ -f "$s" ] || continue
    echo "bench: $s"
    BUILD="$B" sh "$s" "$B/bench" || { echo "bench: $s failed"; exit 1; }
done
# Plots: every tests/bench/*.gp reads CSV from $B/bench and writes docs/bench/*.png.
plots="none (gnuplot not found)"
if command -v gnuplot >/dev/null 2>&1; then
    plots="$(gnuplot --version)"
    for gp in tests/bench/*.gp; do
        [ -f "$gp" ] || continue
        echo "bench: plot $gp"
        gnuplot -e "dir='$B/bench'; out='docs/bench'" "$gp" || { echo "bench: $gp failed"; exit 1; }
    done
else
    echo "bench: gnuplot not found (make deps installs gnuplot-nox): no plots drawn"
fi
{
    echo "# Benchmarks"
    echo
    echo "Generated on $(date -u +%Y-%m-%d) by the command \`make bench\`$( [ "$B" = build ] || echo " (BUILD=$B)")"
    echo "(tests/bench/run.sh: every bench binary, then tests/bench/*.sh, then the gnuplot scripts"
    echo "tests/bench/*.gp; CSV in \`$B/bench/\`, plots in \`docs/bench/\`)."
    echo
    echo "Machine: $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'),"
    echo "$(free -g | awk '/Mem:/{print $2}') GiB RAM); load average at the end: $(cut -d' ' -f1-3 /proc/loadavg);"
    echo "compiler: $(${CC:-cc} --version | head -n 1); plots: $plots."
    echo "Times are medians of several runs; conclusions are stated as ratios measured in the same run."
    echo
    for f in "$B"/bench/*.md; do [ -f "$f" ] && { cat "$f"; echo; }; done
} > docs/BENCHMARKS.md
echo "bench: wrote docs/BENCHMARKS.md"
