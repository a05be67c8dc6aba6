#!/bin/sh
# Turn fuzz/run.sh logs into Markdown table rows for docs/ROBUSTNESS.md:
#   fuzz/report.sh [LOG...]   (default: build/fuzz-runs/*.log)
# Columns: target | executions | coverage (cov / ft) | corpus (units / bytes)
# | wall time | execs/s | findings. A log without an end marker is reported
# as still running, with the figures of its last status line.
[ $# -gt 0 ] || set -- build/fuzz-runs/*.log
echo "| target | executions | coverage (cov / ft) | corpus | wall time | execs/s | findings |"
echo "|---|---:|---|---|---:|---:|---|"
for log in "$@"; do
    [ -f "$log" ] || continue
    t=$(sed -n 's/^# fuzz\/run.sh \([^ ]*\) .*/\1/p' "$log" | head -n 1)
    [ -n "$t" ] || t=$(basename "$log" .log)
    start=$(sed -n 's/^# fuzz\/run.sh .* start=\([0-9]*\).*/\1/p' "$log" | head -n 1)
    # last libFuzzer status line: "#N  KIND cov: C ft: F corp: U/S ..."
    st=$(grep -aE '^#[0-9]+[[:space:]]+[A-Z]+[[:space:]]+cov:' "$log" | tail -n 1)
    execs=$(grep -ao 'stat::number_of_executed_units: [0-9]*' "$log" | tail -n 1 | grep -o '[0-9]*$')
    [ -n "$execs" ] || execs=$(echo "$st" | sed -n 's/^#\([0-9]*\).*/\1/p')
    cov=$(echo "$st" | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$st" | sed -n 's/.* ft: \([0-9]*\).*/\1/p')
    corp=$(echo "$st" | sed -n 's/.* corp: \([^ ]*\).*/\1/p')
    wall=$(sed -n 's/^# wall_seconds=\([0-9]*\).*/\1/p' "$log" | tail -n 1)
    rc=$(sed -n 's/^# wall_seconds=[0-9]* exit=\([0-9]*\).*/\1/p' "$log" | tail -n 1)
    if [ -z "$wall" ]; then
        now=$(date +%s); wall=$(( ${start:-$now} ? now - ${start:-$now} : 0 ))
        state="running"
    elif [ "$rc" = 0 ]; then
        state="0"
    else
        found=$(grep -acE '^==[0-9]+== ?ERROR|deadly signal|Test unit written' "$log")
        # exit 72 = interrupted (-interrupted_exitcode)
        if [ "$rc" = 72 ] && [ "$found" = 0 ]; then state="0 (stopped by hand)"
        else state="**$found (exit $rc)**"; fi
    fi
    rate=-
    [ -n "$execs" ] && [ "${wall:-0}" -gt 0 ] && rate=$((execs / wall))
    h=$((wall / 3600)); m=$((wall % 3600 / 60)); s=$((wall % 60))
    printf '| %s | %s | %s / %s | %s | %dh%02dm%02ds | %s | %s |\n' \
        "$t" "${execs:--}" "${cov:--}" "${ft:--}" "${corp:--}" "$h" "$m" "$s" "$rate" "$state"
done
