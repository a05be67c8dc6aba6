#!/bin/sh
# `make bench`: the tile pyramid (docs/tiles.md). A 2049 x 2049-cell DEM at
# 8 texels (16392 x 16392 pixels, 4225 finest tiles of 256) with a small
# city of 12 roads in one corner, every run --threads 1, fastest of 3.
# Reports finest tiles per second per core (--dense: every tile rendered,
# encoded and written), the sparse saving (default, and --render-all: every
# finest tile rendered; against --dense: files, bytes, time), the fixed
# cost of one process (a shard of one finest tile), and 1 against 2
# processes (--shard 0/2 and 1/2 side by side, then --from-children; wall
# and CPU seconds of each step, the same run's ratios), and 1 against 2
# threads in one process on the city and the 1025^2 fractal (wall, CPU, and
# a cmp of the two outputs). Writes OUT/tiles.md. Needs build/tools/citygen
# and build/tools/demgen (`make bench` builds them).
set -e
OUT=${1:-build/bench}
B=${BUILD:-build}
BIN=$B/roadsplat
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT
python3 -c "
import sys
W = 2050
sys.stdout.buffer.write(b'P5\n%d %d\n255\n' % (W, W) + bytes(((i % W) // 16 + (i // W) // 24) % 200 for i in range(W * W)))" >"$W/dem.pgm"
awk 'BEGIN { for (i = 0; i < 6; i++) { printf "road h%d width 8\n20 %d\n300 %d\nend\nroad v%d width 8\n%d 20\n%d 300\nend\n", i, 30 + 50 * i, 30 + 50 * i, i, 30 + 50 * i, 30 + 50 * i } }' >"$W/city.txt"
O="--quiet --texels 8 --threads 1"
IN="$W/dem.pgm $W/city.txt"
now() { date +%s.%N; }
fmt() { printf %.${2:-2}f "$1"; }
calc() { echo "$*" | bc -l; }
# Every run writes a new folder, and none is removed before the end: ext4
# allocating inodes right after thousands were deleted scans for recently
# deleted ones (perf: recently_deleted, find_get_block_common), which would
# be timed as the runs' system time.
echo 0 >"$W/n"
fresh() { # a new folder name (a file counts: the callers run in subshells)
    k=$(($(cat "$W/n") + 1)); echo "$k" >"$W/n"; echo "$W/o$k"
}
best() { # command... (the output folder last): the fastest of 3 runs, seconds; the last folder in $W/last
    b=
    for k in 1 2 3; do
        o=$(fresh); echo "$o" >"$W/last"
        t0=$(now); "$@" "$o"; t=$(calc "$(now) - $t0")
        if [ -z "$b" ] || [ "$(calc "$t < $b")" = 1 ]; then b=$t; fi
    done
    echo "$b"
}
files() { find "$(cat "$W/last")" -name '*.png' | wc -l; }
kib() { du -sk "$(cat "$W/last")" | cut -f1; }

dense=$(best "$BIN" tiles $O --dense $IN); de_files=$(files); de_kib=$(kib)
full=$(best "$BIN" tiles $O --render-all $IN); fu_files=$(files); fu_kib=$(kib)
sparse=$(best "$BIN" tiles $O $IN); sp_files=$(files); sp_kib=$(kib)
"$BIN" tiles --texels 8 --threads 1 $IN "$(fresh)" 2>"$W/msg"
rendered=$(sed -n 's/.*tiles: \([0-9]*\) rendered.*/\1/p' "$W/msg")
direct=$(sed -n 's/.* \([0-9]*\) terrain-only rendered.*/\1/p' "$W/msg")
setup=$(best "$BIN" tiles $O --dense --shard 0/4225 $IN)

# 1 against 2 processes: wall of the pair of shards and of the merge, and
# the CPU seconds (user + system) of each process, for OPTS
cpu() { # file: user + sys seconds written by /usr/bin/time -f "%U %S"
    awk '{ s = $1 + $2 } END { print s }' "$1"
}
two() { # OPTS: prints "pair_wall merge_wall cpu0 cpu1 cpu_merge cpu_one wall_one" (fastest pair of 3)
    bp=; for k in 1 2 3; do
        o=$(fresh)
        t0=$(now)
        /usr/bin/time -f "%U %S" -o "$W/c0" "$BIN" tiles $O $1 --shard 0/2 $IN "$o" & p=$!
        /usr/bin/time -f "%U %S" -o "$W/c1" "$BIN" tiles $O $1 --shard 1/2 $IN "$o"; wait $p
        t1=$(now)
        /usr/bin/time -f "%U %S" -o "$W/cm" "$BIN" tiles $O $1 --from-children $IN "$o"
        t2=$(now)
        pw=$(calc "$t1 - $t0"); mw=$(calc "$t2 - $t1")
        if [ -z "$bp" ] || [ "$(calc "$pw + $mw < $bp + $bm")" = 1 ]; then
            bp=$pw; bm=$mw; c0=$(cpu "$W/c0"); c1=$(cpu "$W/c1"); cm=$(cpu "$W/cm")
        fi
    done
    /usr/bin/time -f "%U %S" -o "$W/c" "$BIN" tiles $O $1 $IN "$(fresh)"; c=$(cpu "$W/c")
    echo "$bp $bm $c0 $c1 $cm $c"
}
# control: two whole --dense runs at once (no sharding at all): what this
# machine gives a second process, whatever roadsplat does
o1=$(fresh); o2=$(fresh); t0=$(now)
/usr/bin/time -f "%U %S" -o "$W/k0" "$BIN" tiles $O --dense $IN "$o1" & p=$!
/usr/bin/time -f "%U %S" -o "$W/k1" "$BIN" tiles $O --dense $IN "$o2"; wait $p
k_wall=$(calc "$(now) - $t0"); k_c0=$(cpu "$W/k0"); k_c1=$(cpu "$W/k1")
/usr/bin/time -f "%U %S" -o "$W/k" "$BIN" tiles $O --dense $IN "$(fresh)"; k_c=$(cpu "$W/k")
set -- $(two --dense); d_pair=$1 d_merge=$2 d_c0=$3 d_c1=$4 d_cm=$5 d_c=$6
set -- $(two --render-all); f_pair=$1 f_merge=$2 f_c0=$3 f_c1=$4 f_cm=$5 f_c=$6
set -- $(two ""); s_pair=$1 s_merge=$2 s_c0=$3 s_c1=$4 s_cm=$5 s_c=$6
# 1 against 2 threads in one process (worker threads: box filters, PNG
# compression, SHA-256, file writes; docs/tiles.md "Threads"): the city
# scene (tests/tools/citygen) at 16 texels and the 1025^2 fractal
# (tests/tools/demgen, one road) at 8 texels --dense; the runs of 1 and 2
# threads interleaved, fastest wall of 5 each with its CPU seconds (user +
# system), whether the two outputs are the same bytes (tiles, tiles.json,
# the logs but their run id line), and a control: two 1-thread runs at once
# (fastest of 3), 2 x one run's wall over theirs: what the machine gave a
# second thread then (2.00 on two free cores)
"$B/tools/citygen" "$W/city.pgm" "$W/city_roads.txt"
"$B/tools/demgen" 1025 "$W/frac.pgm"
printf 'road main width 6\n300 300\n700 450\n900 980\nend\n' >"$W/frac_roads.txt"
same_out() { # two output folders: "yes" when every byte is the same (but the logs' run ids)
    diff -r -x .tiles-log "$1" "$2" >/dev/null || { echo "**no**"; return; }
    for f in "$1"/.tiles-log/*.log; do
        grep -v '^run ' "$f" >"$W/la"; grep -v '^run ' "$2/.tiles-log/$(basename "$f")" >"$W/lb" 2>/dev/null
        cmp -s "$W/la" "$W/lb" || { echo "**no**"; return; }
    done
    echo yes
}
threads_row() { # name, options, inputs...: "| name | wall 1 | wall 2 | ratio | cpu 1 | cpu 2 | same |"
    name=$1 opts=$2; shift 2
    w1=; w2=
    for k in 1 2 3 4 5; do
        for t in 1 2; do
            o=$(fresh)
            t0=$(now)
            /usr/bin/time -f "%U %S" -o "$W/ct" "$BIN" tiles --quiet $opts --threads $t "$@" "$o"
            w=$(calc "$(now) - $t0"); c=$(cpu "$W/ct")
            eval "b=\$w$t"
            if [ -z "$b" ] || [ "$(calc "$w < $b")" = 1 ]; then eval "w$t=$w; c$t=$c; o$t=$o"; fi
        done
    done
    # control: two 1-thread runs at once, what this machine gives a second thread now
    wp=
    for k in 1 2 3; do
        oa=$(fresh); ob=$(fresh); t0=$(now)
        "$BIN" tiles --quiet $opts --threads 1 "$@" "$oa" & p=$!
        "$BIN" tiles --quiet $opts --threads 1 "$@" "$ob"; wait $p
        w=$(calc "$(now) - $t0")
        if [ -z "$wp" ] || [ "$(calc "$w < $wp")" = 1 ]; then wp=$w; fi
    done
    echo "| $name | $(fmt "$w1") | $(fmt "$w2") | $(fmt "$(calc "$w1 / $w2")") | $(fmt "$c1") | $(fmt "$c2") | $(same_out "$o1" "$o2") | $(fmt "$(calc "2 * $w1 / $wp")") |"
}
load0=$(cut -d' ' -f1-3 /proc/loadavg)
t_city=$(threads_row "city (\`sc_city_default\`, 400 x 350 cells of 5 m, 1000 roads), 16 texels: 550 finest tiles" \
    "--cell-size 5 --z-scale 0.01 --texels 16" "$W/city.pgm" "$W/city_roads.txt")
t_frac=$(threads_row "1025^2 fractal, one road, 8 texels, --dense: 1089 finest tiles" \
    "--cell-size 5 --z-scale 0.01 --texels 8 --dense" "$W/frac.pgm" "$W/frac_roads.txt")
load1=$(cut -d' ' -f1-3 /proc/loadavg)

cores=$(nproc)
finest=4225
load=$(cut -d' ' -f1-3 /proc/loadavg)
row() { # name one_wall pair merge c0 c1 cm c
    echo "| $1 | $(fmt "$2") | $(fmt "$3") + $(fmt "$4") | $(fmt "$(calc "$2 / ($3 + $4)")") | $(fmt "$5") / $(fmt "$6") / $(fmt "$7") | $(fmt "$8") | $(fmt "$(calc "($2 - $setup) / 2 + $setup + $4")") |"
}
{
    echo "## Tile pyramid (roadsplat tiles)"
    echo
    echo "\`tests/bench/tiles.sh\`: 2049 x 2049-cell DEM at 8 texels (16392 x 16392 pixels, $finest finest"
    echo "tiles of 256, levels 0..7, complete up to level 4), a city of 12 roads in one corner; fastest of 3 runs,"
    echo "\`--threads 1\`; $cores cores, load average $load at the end."
    echo
    echo "| run | seconds | finest tiles per second per core | files | KiB on disk |"
    echo "|---|---|---|---|---|"
    echo "| --dense (every tile rendered and written) | $(fmt "$dense") | $(fmt "$(calc "$finest / $dense")" 0) | $de_files | $de_kib |"
    echo "| --render-all (sparse files, every finest tile rendered) | $(fmt "$full") | $(fmt "$(calc "$finest / $full")" 0) | $fu_files | $fu_kib |"
    echo "| sparse (default: $rendered finest tiles rendered, $direct terrain-only tiles at level 4) | $(fmt "$sparse") | $(fmt "$(calc "$finest / $sparse")" 0) | $sp_files | $sp_kib |"
    echo "| one process's fixed cost (a shard of one finest tile) | $(fmt "$setup") | | | |"
    echo
    echo "Sparse saving against --dense: $(fmt "$(calc "$de_files / $sp_files")" 1)x fewer files,"
    echo "$(fmt "$(calc "$de_kib / $sp_kib")" 1)x fewer bytes, $(fmt "$(calc "$dense / $sparse")")x the speed"
    echo "($(fmt "$(calc "$dense / $full")")x with --render-all, which renders every finest tile)."
    echo
    echo "1 against 2 processes (--shard 0/2 and 1/2 side by side, then --from-children):"
    echo
    echo "| run | 1 process s | 2 processes s (shards + merge) | speed-up | CPU s: shard 0 / shard 1 / merge | CPU s of 1 process | ideal s (fixed cost not shared) |"
    echo "|---|---|---|---|---|---|---|"
    row "--dense" "$dense" "$d_pair" "$d_merge" "$d_c0" "$d_c1" "$d_cm" "$d_c"
    row "--render-all" "$full" "$f_pair" "$f_merge" "$f_c0" "$f_c1" "$f_cm" "$f_c"
    row "sparse (default)" "$sparse" "$s_pair" "$s_merge" "$s_c0" "$s_c1" "$s_cm" "$s_c"
    echo
    echo "The ideal column is what two free cores would give: the work after the fixed cost halved, the fixed"
    echo "cost paid by each process, plus the merge as measured (docs/tiles.md, \"1 and 2 processes\")."
    echo
    echo "Control, no sharding: two whole --dense runs at once took $(fmt "$k_wall") s (CPU $(fmt "$k_c0") and $(fmt "$k_c1") s;"
    echo "alone $(fmt "$k_c") s CPU, $(fmt "$dense") s): this machine ran 2 processes $(fmt "$(calc "2 * $dense / $k_wall")")x as fast as 1 (ideal 2.00)."
    echo
    echo "1 against 2 threads in one process (\`--threads\`; the workers box-filter, compress, hash and write"
    echo "the tiles): the runs interleaved, fastest wall of 5 each, CPU = user + system seconds of that run;"
    echo "control = two 1-thread runs at once against one after the other (what this machine gave a second"
    echo "thread; 2.00 on two free cores); load average $load0 before and $load1 after these runs."
    echo
    echo "| run | 1 thread s | 2 threads s | speed-up | CPU s, 1 thread | CPU s, 2 threads | same bytes | control |"
    echo "|---|---|---|---|---|---|---|---|"
    echo "$t_city"
    echo "$t_frac"
} >"$OUT/tiles.md"
cat "$OUT/tiles.md"
