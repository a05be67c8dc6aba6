#!/bin/bash
# A tile pyramid on a Slurm cluster (docs/tiles.md): one array task per
# shard, then one merge job once every shard has finished.
#
#   export DEM=dem.tif ROADS=roads.gpkg OUT=/shared/tiles OPTS="--texels 8"
#   jid=$(sbatch --parsable --array=0-15 tiles_slurm.sh)        # 16 shards
#   sbatch --dependency=afterok:$jid tiles_slurm.sh merge
#
# OUT must be on a file system every node sees. A task that dies is rerun
# with `sbatch --array=I tiles_slurm.sh` (it resumes: tiles whose file has
# the logged SHA-256 are kept). ROADSPLAT names the executable.
#SBATCH --job-name=roadsplat-tiles
#SBATCH --cpus-per-task=4
#SBATCH --mem=2G
#SBATCH --time=04:00:00
set -euo pipefail
: "${DEM:?set DEM}" "${ROADS:?set ROADS}" "${OUT:?set OUT}"
ROADSPLAT=${ROADSPLAT:-roadsplat}
OPTS=${OPTS:-}
threads=${SLURM_CPUS_PER_TASK:-1}
if [ "${1:-}" = merge ]; then
    # shellcheck disable=SC2086
    exec "$ROADSPLAT" tiles --quiet --threads "$threads" --from-children $OPTS "$DEM" "$ROADS" "$OUT"
fi
: "${SLURM_ARRAY_TASK_ID:?run as an array job (sbatch --array=0-N-1)}"
count=${SLURM_ARRAY_TASK_COUNT:-$(( ${SLURM_ARRAY_TASK_MAX:?} - ${SLURM_ARRAY_TASK_MIN:-0} + 1 ))}
# shellcheck disable=SC2086
exec "$ROADSPLAT" tiles --quiet --threads "$threads" --resume --shard "$SLURM_ARRAY_TASK_ID/$count" $OPTS "$DEM" "$ROADS" "$OUT"
