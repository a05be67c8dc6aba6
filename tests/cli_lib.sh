# Shared prelude of the CLI test scripts (sourced): a temporary folder $T
# removed on exit, pass/fail counters, and ok / bad / check.
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
pass=0; fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
check() { # description, command...
    d=$1; shift
    if "$@"; then ok; else bad "$d"; fi
}
# The small reference scene: DIR/dem.pgm (31x21 P2, sample i = i mod 97) and
# DIR/roads.txt (two roads).
ref_scene() {
    printf 'P2\n31 21\n255\n' >"$1/dem.pgm"
    awk 'BEGIN { for (i = 0; i < 651; i++) printf "%d%s", i % 97, (i % 31 == 30) ? "\n" : " " }' >>"$1/dem.pgm"
    cat >"$1/roads.txt" <<'R'
# two roads
road main width 6
2 2
28 20
end
road side width 3
0 15
30 15
end
R
}
# need_gdal NAME BIN TOOL...: exit with a SKIP line and "NAME: 0 passed, 0
# failed" unless BIN has the GDAL module and every TOOL is on the PATH
need_gdal() {
    n=$1 b=$2; shift 2
    "$b" convert "$T/none.geojson" "$T/none.txt" 2>"$T/e"
    if grep -q "no GDAL support" "$T/e"; then
        echo "SKIP $n: $b was built without GDAL (make deps installs libgdal-dev)"; echo "$n: 0 passed, 0 failed"; exit 0
    fi
    for tool in "$@"; do
        command -v "$tool" >/dev/null 2>&1 && continue
        echo "SKIP $n: $tool is missing (make deps installs gdal-bin)"; echo "$n: 0 passed, 0 failed"; exit 0
    done
}
