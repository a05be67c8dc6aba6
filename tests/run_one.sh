#!/bin/sh
# One job of tests/run.sh: run_one.sh OUTDIR INDEX COMMAND... runs COMMAND
# with its output in OUTDIR/INDEX.log, and writes its exit status and
# tenths of a second to OUTDIR/INDEX.rc and OUTDIR/INDEX.time.
out=$1; i=$2; shift 2
t0=$(date +%s%N 2>/dev/null || echo 0)
"$@" >"$out/$i.log" 2>&1; rc=$?
t1=$(date +%s%N 2>/dev/null || echo 0)
echo "$(( (t1 - t0) / 100000000 ))" >"$out/$i.time"
echo "$rc" >"$out/$i.rc"
