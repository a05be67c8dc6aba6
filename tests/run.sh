#!/bin/sh
# Runs every test binary, the CLI tests and the fuzz-corpus replays, then
# prints one closing "N passed, N failed" line over all of them.
B=${BUILD:-build}
# Jobs run TEST_JOBS at a time (default: one per core) through xargs; their
# results are read back and printed in the order they were listed. The
# slow ones (seconds on 2 cores, December 2026) start first, so the last
# job to start is a short one.
J=${TEST_JOBS:-$(nproc 2>/dev/null || echo 1)}
slow="cli_render_test cli_gdal_test cli_odr_test cli_tiles_test test_linesym cli_badinput_test cli_surface_paths_test"
total_p=0; total_f=0; out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
n=0; queue=; : >"$out/first"; : >"$out/rest"; : >"$out/last"
job() { # name, command... (no spaces or quotes inside the words)
    n=$((n + 1)); echo "$n" >>"$out/order"; echo "$1" >"$out/$n.name"
    q=${queue:-rest}; case " $slow " in *" $1 "*) q=${queue:-first} ;; esac
    shift; echo "$out $n $*" >>"$out/$q"
}
count() { # index
    name=$(cat "$out/$1.name"); log=$out/$1.log
    rc=$(cat "$out/$1.rc" 2>/dev/null || echo 127); d=$(cat "$out/$1.time" 2>/dev/null || echo 0)
    line=$(grep -E '[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1)
    p=$(echo "$line" | sed -n 's/^\(.*[^0-9]\)\{0,1\}\([0-9][0-9]*\) passed.*/\2/p'); f=$(echo "$line" | sed -n 's/.*passed, \([0-9][0-9]*\) failed.*/\1/p')
    [ -n "$p" ] || p=0; [ -n "$f" ] || f=0
    if [ "$rc" -ne 0 ] && [ "$f" = 0 ]; then f=1; fi
    if [ "$f" != 0 ]; then cat "$log"; echo "FAILED: $name (exit $rc)"; else echo "ok   $name: $p passed ($((d / 10)).$((d % 10)) s)"; fi
    grep '^SKIP' "$log" | sed "s/^/     $name: /"
    total_p=$((total_p + p)); total_f=$((total_f + f))
}
# A decimal-comma locale for test_locale and the CLI locale check. Machines
# (and CI images) often have none installed, so build de_DE.UTF-8 from the
# glibc sources into the build folder and point LOCPATH there; without
# localedef or the sources the tests print a SKIP line instead.
loc=$B/locale
if [ ! -f "$loc/de_DE.UTF-8/LC_NUMERIC" ] && command -v localedef >/dev/null 2>&1 &&
    [ -f /usr/share/i18n/locales/de_DE ]; then
    mkdir -p "$loc" && localedef -i de_DE -f UTF-8 "$loc/de_DE.UTF-8" >/dev/null 2>&1
fi
if [ -f "$loc/de_DE.UTF-8/LC_NUMERIC" ]; then LOCPATH=$(cd "$loc" && pwd); export LOCPATH; fi
for t in "$B"/tests/test_*; do
    [ -x "$t" ] || continue
    job "$(basename "$t")" "$t"
done
# Large crasher inputs are generated (tests/gen_crashers.sh), not stored.
gen=$B/crashers-gen
gen_f=0; sh tests/gen_crashers.sh "$gen" || { echo "FAILED: tests/gen_crashers.sh"; gen_f=1; }
for r in "$B"/fuzz/*-replay; do
    [ -x "$r" ] || continue
    tgt=$(basename "$r" -replay)
    extra=; [ -d "$gen/$tgt" ] && extra="$gen/$tgt"
    job "fuzz_replay_$tgt" "$r" fuzz/"$tgt"/corpus tests/crashers/"$tgt" $extra
done
for s in tests/cli*_test.sh; do
    [ -f "$s" ] || continue
    job "$(basename "$s" .sh)" sh "$s" "$B/roadsplat"
done
# make install into a temporary prefix, consumers built through pkg-config;
# alone, after the rest: its PREFIX rewrites the build's config and so
# relinks $B/roadsplat, which the other jobs run.
queue=last
for s in tests/install*_test.sh; do
    [ -f "$s" ] || continue
    job "$(basename "$s" .sh)" sh "$s" "$B"
done
cat "$out/first" "$out/rest" | xargs -L 1 -P "$J" sh tests/run_one.sh
xargs -L 1 -P 1 sh tests/run_one.sh <"$out/last"
for i in $(cat "$out/order"); do count "$i"; done
total_f=$((total_f + gen_f))
echo "$total_p passed, $total_f failed"
[ "$total_f" = 0 ]
