#!/bin/sh
# `roadsplat tiles --threads N` (docs/tiles.md, "Threads"): the worker threads
# box-filter, compress, hash and write the tiles, and the results are
# committed in one order, so the output is the same bytes for any N: every
# tile file, tiles.json, the logs (but their `run RUNID` line), the MBTiles
# file, shards + merge and a resume run with different counts, the normal
# layer with a halo, and a worker's error (one line, exit 1, no temporary).
# Usage: sh tests/cli_tiles_threads_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_tiles_threads_test.sh ROADSPLAT}
D=$(cd "$(dirname "$0")" && pwd)
. "$D/cli_lib.sh"
ref_scene "$T"
IN="$T/dem.pgm $T/roads.txt"
# 2400 x 1600 pixels: 10 x 7 finest tiles of 256, levels 0..4, so the
# queue of jobs (4 per worker) fills and the workers finish out of order
O="--texels 80"
logs_same() { # the logs of two folders, but their run ids
    for f in "$1"/.tiles-log/*.log; do
        g="$2/.tiles-log/$(basename "$f")"
        [ -f "$g" ] || return 1
        grep -v '^run ' "$f" >"$T/la"; grep -v '^run ' "$g" >"$T/lb"
        cmp -s "$T/la" "$T/lb" || return 1
    done
}
same_all() { diff -r -x .tiles-log "$1" "$2" >/dev/null && logs_same "$1" "$2"; }

# 1. dense and sparse pyramids: 1, 2 and 3 threads
for mode in --dense ""; do
    name=sparse; [ -n "$mode" ] && name=dense
    for t in 1 2 3; do
        "$BIN" tiles --quiet $mode --threads $t $O $IN "$T/p$name$t" || bad "$name --threads $t exits 0"
    done
    check "$name: tiles, tiles.json and logs of 2 threads = 1 thread" same_all "$T/p${name}1" "$T/p${name}2"
    check "$name: tiles, tiles.json and logs of 3 threads = 1 thread" same_all "$T/p${name}1" "$T/p${name}3"
    check "$name: some tiles written" test "$(find "$T/p${name}1" -name '*.png' | wc -l)" -gt 20
done

# 2. the normal layer with a halo (the halo ring is made on the main thread)
for t in 1 3; do
    "$BIN" tiles --quiet --normals --halo 2 --threads $t --texels 40 $IN "$T/nh$t" || bad "--normals --halo --threads $t"
done
check "--normals --halo 2: 3 threads = 1 thread" same_all "$T/nh1" "$T/nh3"

# 3. shards and merge with other thread counts = one run of 1 thread
"$BIN" tiles --quiet --shard 0/2 --threads 3 $O $IN "$T/sh" || bad "shard 0 with 3 threads"
"$BIN" tiles --quiet --shard 1/2 --threads 1 $O $IN "$T/sh" || bad "shard 1 with 1 thread"
"$BIN" tiles --quiet --from-children --threads 2 $O $IN "$T/sh" || bad "merge with 2 threads"
check "2 shards (3 and 1 threads) + merge (2 threads) = one run" sh -c "diff -r -x .tiles-log '$T/sh' '$T/psparse1' >/dev/null"

# 4. resume with 2 threads after tiles were lost or changed = one run
cp -r "$T/pdense1" "$T/rs"
rm "$T/rs/4/3/2.png" "$T/rs/3/4/1.png"
printf 'x' >>"$T/rs/4/5/5.png"
check "resume with 2 threads remade the 3 tiles" sh -c "'$BIN' tiles --resume --dense --threads 2 $O $IN '$T/rs' 2>&1 | grep -q ': 2 rendered, 3 written'"
check "resume with 2 threads = one run" sh -c "diff -r -x .tiles-log '$T/rs' '$T/pdense1' >/dev/null"

# 5. MBTiles: the same file, byte for byte (same base name: it is metadata)
if "$BIN" tiles --quiet --format mbtiles --threads 1 $O $IN "$T/m1.mbtiles" 2>/dev/null; then
    for t in 2 3; do
        mkdir "$T/m$t"
        "$BIN" tiles --quiet --format mbtiles --threads $t $O $IN "$T/m$t/m1.mbtiles" || bad "mbtiles --threads $t"
        check "MBTiles file of $t threads = 1 thread, byte for byte" cmp -s "$T/m1.mbtiles" "$T/m$t/m1.mbtiles"
    done
else
    echo "SKIP: no MBTiles module: the MBTiles file is not compared"
fi

# 6. a worker's error: one line, exit 1, no temporary left, on any count
for t in 1 2 3; do
    mkdir -p "$T/er$t/4" && ln -s "$T" "$T/er$t/4/3"
    "$BIN" tiles --quiet --dense --threads $t $O $IN "$T/er$t" 2>"$T/e$t"
    rc=$?
    check "a planted link, $t threads: exit 1" test "$rc" = 1
    check "a planted link, $t threads: one line naming it" sh -c "test \$(wc -l <'$T/e$t') = 1 && grep -q 'er$t/4/3: is a symbolic link' '$T/e$t'"
    check "a planted link, $t threads: no temporary, no manifest" sh -c "test -z \"\$(find '$T/er$t' -name '*.part')\" && test ! -e '$T/er$t/tiles.json'"
done

# 7. several failing tiles (links at levels 2-4): the workers take ready jobs
# out of order, yet the one line is the first failure in the walk's order,
# the line one thread prints
for t in 1 2 3; do
    for d in 4/1 4/3 3/0 3/1 2/0; do mkdir -p "$T/em$t/${d%/*}" && ln -s "$T" "$T/em$t/$d"; done
    "$BIN" tiles --quiet --dense --threads $t $O $IN "$T/em$t" 2>"$T/f$t"
    rc=$?
    check "several planted links, $t threads: exit 1, one line" sh -c "test $rc = 1 && test \$(wc -l <'$T/f$t') = 1"
    sed "s|em$t/|emN/|" "$T/f$t" >"$T/g$t"
    [ $t = 1 ] || check "several planted links, $t threads: the 1-thread line" cmp -s "$T/g1" "$T/g$t"
    check "several planted links, $t threads: no temporary, no manifest" sh -c "test -z \"\$(find '$T/em$t' -name '*.part')\" && test ! -e '$T/em$t/tiles.json'"
done

echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
