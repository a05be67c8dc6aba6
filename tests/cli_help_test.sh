#!/bin/sh
# Every option a command accepts is listed in that command's --help (issue 26:
# `render` took --gdal-trust and --max-image-pixels without saying so).
# Behavioural, so that no parser list has to be kept in step with this file:
# the candidates are every --option named in any command's help or written as
# a string in the CLI's sources; a command accepts one when `CMD OPT 1` does
# not answer "unknown option" (a value-taking option gets "1", a flag makes
# "1" a missing positional argument: nothing runs).
# Usage: sh tests/cli_help_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_help_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)/cli

cmds="main render tiles mesh convert"
run() { # command, args...
    c=$1; shift
    if [ "$c" = main ]; then "$BIN" "$@"; else "$BIN" "$c" "$@"; fi
}
for c in $cmds; do run "$c" --help >"$T/help.$c" 2>&1 </dev/null; done
cat "$T"/help.* >"$T/all"
# a help that refers to "every splat option of roadsplat --help" lists those
for c in $cmds; do
    cp "$T/help.$c" "$T/names.$c"
    grep -q 'every splat option of roadsplat --help' "$T/help.$c" && cat "$T/help.main" >>"$T/names.$c"
done
[ -d "$SRC" ] && cat "$SRC"/*.c "$SRC"/*.cpp >>"$T/all" 2>/dev/null
grep -o -- '--[a-z][a-z0-9-]*' "$T/all" | sort -u >"$T/candidates"
n=$(wc -l <"$T/candidates")
check "at least 40 candidate options found ($n)" test "$n" -ge 40
for c in $cmds; do
    missing=
    while read -r opt; do
        out=$(run "$c" "$opt" 1 2>&1 </dev/null)
        case $out in *"unknown option"*) continue ;; esac
        [ "$opt" = --help ] && continue # every command takes it
        # accepted: the help names it as an option (followed by a blank, '=', ',', '|', ']' or a line end)
        grep -q -e "$opt\$" -e "$opt[] =,|]" "$T/names.$c" || missing="$missing $opt"
    done <"$T/candidates"
    check "roadsplat $c --help lists every option it accepts (missing:$missing)" test -z "$missing"
done
echo "cli_help: $pass passed, $fail failed"
[ "$fail" = 0 ]
