#!/bin/sh
# Runs every test binary, the CLI tests and the fuzz-corpus replays, then
# prints one closing "N passed, N failed" line over all of them.
B=${BUILD:-build}
total_p=0; total_f=0; log=$(mktemp); trap 'rm -f "$log"' EXIT
count() { # name, command...
    name=$1; shift
    "$@" >"$log" 2>&1; rc=$?
    line=$(grep -E '[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1)
    p=$(echo "$line" | sed -n 's/^\(.*[^0-9]\)\{0,1\}\([0-9][0-9]*\) passed.*/\2/p'); f=$(echo "$line" | sed -n 's/.*passed, \([0-9][0-9]*\) failed.*/\1/p')
    [ -n "$p" ] || p=0; [ -n "$f" ] || f=0
    if [ $rc -ne 0 ] && [ "$f" = 0 ]; then f=1; fi
    if [ "$f" != 0 ]; then cat "$log"; echo "FAILED: $name (exit $rc)"; else echo "ok   $name: $p passed"; fi
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
    count "$(basename "$t")" "$t"
done
# Large crasher inputs are generated (tests/gen_crashers.sh), not stored.
gen=$B/crashers-gen
sh tests/gen_crashers.sh "$gen" || echo "FAILED: tests/gen_crashers.sh"
for r in "$B"/fuzz/*-replay; do
    [ -x "$r" ] || continue
    tgt=$(basename "$r" -replay)
    extra=; [ -d "$gen/$tgt" ] && extra="$gen/$tgt"
    count "fuzz replay $tgt" "$r" fuzz/"$tgt"/corpus tests/crashers/"$tgt" $extra
done
for s in tests/cli*_test.sh; do
    [ -f "$s" ] || continue
    count "$(basename "$s" .sh)" sh "$s" "$B/roadsplat"
done
# make install into a temporary prefix, consumers built through pkg-config.
for s in tests/install*_test.sh; do
    [ -f "$s" ] || continue
    count "$(basename "$s" .sh)" sh "$s" "$B"
done
echo "$total_p passed, $total_f failed"
[ "$total_f" = 0 ]
