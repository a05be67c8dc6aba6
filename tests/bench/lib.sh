# Shell helpers of the bench scripts that read the CLI's --stats JSON
# (sourced by tests/bench/write.sh and obj.sh; not a bench: run.sh skips it).
# fastest: the smallest of the numbers on stdin, one a line.
fastest() { sort -n | head -n 1; }
# field NAME FILE: the first number after "NAME": in FILE.
field() { sed -n "s/.*\"$1\": \\([0-9.]*\\).*/\\1/p" "$2" | head -n 1; }
