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
