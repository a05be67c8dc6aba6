#!/bin/sh
# Run one libFuzzer target: fuzz/run.sh TARGET [SECONDS | runs=N]
# Uses $BUILD/fuzz-bin/TARGET (built by `make fuzz`), the target's dictionary
# when present, a working corpus in $BUILD/fuzz-corpus/TARGET (seeded from
# fuzz/TARGET/corpus, which is never written to), crash artifacts in
# $BUILD/fuzz-artifacts/TARGET/ and a log ($FUZZ_LOG, default
# $BUILD/fuzz-runs/TARGET.log). Exit status: 0 = no finding.
set -u
t=${1:?usage: fuzz/run.sh TARGET [SECONDS | runs=N]}
len=${2:-30}
B=${BUILD:-build}
bin=$B/fuzz-bin/$t
[ -x "$bin" ] || { echo "fuzz/run.sh: $bin missing (run make fuzz)" >&2; exit 2; }
[ -d "fuzz/$t/corpus" ] || { echo "fuzz/run.sh: no fuzz/$t/corpus" >&2; exit 2; }
corpus=$B/fuzz-corpus/$t
art=$B/fuzz-artifacts/$t/
log=${FUZZ_LOG:-$B/fuzz-runs/$t.log}
mkdir -p "$corpus" "$art" "$(dirname "$log")"
cp -n fuzz/"$t"/corpus/* "$corpus"/ 2>/dev/null || true
case $len in
    runs=*) limit="-runs=${len#runs=}" ;;
    *) limit="-max_total_time=$len" ;;
esac
dict=
[ -f "fuzz/$t/$t.dict" ] && dict="-dict=fuzz/$t/$t.dict"
start=$(date +%s)
echo "# fuzz/run.sh $t $len start=$start" >"$log"
# demimage: the leak check needs full unwinding through OpenImageIO (see
# fuzz/demimage/fuzz.c), which costs 3x, and OpenImageIO trying every reader
# it has on each bad file (try_all_readers) costs 4x more, all inside
# OpenImageIO. So the fuzzing loop skips both; every corpus file is then
# replayed once with both back on (below), leak check included.
fast=
if [ "$t" = demimage ]; then
    fast="-detect_leaks=0"
    export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=1:detect_leaks=0"
    export OPENIMAGEIO_OPTIONS=try_all_readers=0
fi
# -timeout: one input taking >10 s is a finding (a hang); -rss_limit_mb
# bounds memory so an unchecked allocation shows up as a finding too.
"$bin" $dict -artifact_prefix="$art" -timeout=10 -rss_limit_mb=2048 $fast \
    -max_len=${FUZZ_MAX_LEN:-8192} -print_final_stats=1 $limit "$corpus" >>"$log" 2>&1
rc=$?
if [ $rc -eq 0 ] && [ -n "$fast" ]; then
    unset ASAN_OPTIONS OPENIMAGEIO_OPTIONS
    echo "# replay of the corpus with leak check and all readers" >>"$log"
    "$bin" -artifact_prefix="$art" -timeout=10 -rss_limit_mb=2048 -runs=0 "$corpus" >>"$log.replay" 2>&1
    rc=$?
    sed 's/^/replay: /' "$log.replay" >>"$log"; rm -f "$log.replay"
fi
end=$(date +%s)
echo "# wall_seconds=$((end - start)) exit=$rc" >>"$log"
# Executions: libFuzzer's final stats; when those are missing (they can land
# in demimage's captured stderr on an interrupt), its last status line.
n=$(grep -ao 'stat::number_of_executed_units: [0-9]*' "$log" | grep -o '[0-9]*$')
[ -n "$n" ] || n=$(grep -aE '^#[0-9]+[[:space:]]' "$log" | tail -n 1 | sed 's/^#\([0-9]*\).*/\1/')
if [ $rc -eq 72 ]; then
    # libFuzzer's exit code for SIGINT/SIGTERM (-interrupted_exitcode):
    # stopped by hand, not a finding
    echo "fuzz $t: interrupted after $n runs in $((end - start)) s" >&2
    exit 3
fi
if [ $rc -ne 0 ]; then
    echo "fuzz $t: FINDING (exit $rc), see $log and $art" >&2
    grep -E '^(==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)' "$log" | head -n 5 >&2
    exit 1
fi
echo "fuzz $t: ok, $n runs in $((end - start)) s"
