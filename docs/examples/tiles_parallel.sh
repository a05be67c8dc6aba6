#!/bin/sh
# A tile pyramid by GNU parallel (docs/tiles.md): N shards as N jobs, here
# or over ssh hosts, then the merge. Usage:
#   tiles_parallel.sh N DEM ROADS OUTDIR [roadsplat tiles options...]
# Extra parallel options come from PARALLEL_OPTS, e.g.
#   PARALLEL_OPTS="--sshlogin 4/host1,4/host2 --workdir /shared" (OUTDIR on a shared file system)
# A failed run is finished by running the same command again: --joblog and
# --resume-failed rerun only the shards that failed, and each shard keeps
# the tiles it had finished (--resume).
set -e
N=$1 DEM=$2 ROADS=$3 OUT=$4
shift 4
ROADSPLAT=${ROADSPLAT:-roadsplat}
mkdir -p "$OUT"
# shellcheck disable=SC2086
seq 0 $((N - 1)) | parallel $PARALLEL_OPTS --halt soon,fail=1 --joblog "$OUT.joblog" --resume-failed \
    "$ROADSPLAT" tiles --quiet --resume --shard {}/"$N" "$@" "$DEM" "$ROADS" "$OUT"
"$ROADSPLAT" tiles --quiet --from-children "$@" "$DEM" "$ROADS" "$OUT"
