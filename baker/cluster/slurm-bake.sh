#!/bin/sh
# Submits a bake of SCENE to Slurm as array jobs: the sample, aim and train stages in N shards
# each, then the merge, each stage starting when every task of the one before has succeeded
# (afterok). Every task must see the same scene and model folder (a shared file system), where
# the bake cache MODEL.bake-cache/ collects the shards' files. Prints the merge's job id.
#
#   usage: slurm-bake.sh SCENE N [rrf bake options: --quality Q --seed S -o MODEL ...]
#   RRF=/path/to/rrf to run another binary than the one on PATH;
#   SBATCH_OPTIONS="--partition=gpu --time=1:00:00" for options of every job.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: $0 SCENE SHARDS [rrf bake options]" >&2
    exit 2
fi
scene=$1
shards=$2
shift 2
rrf=${RRF:-rrf}
options=${SBATCH_OPTIONS:-}
after=""
for stage in sample aim train; do
    # shellcheck disable=SC2086 # word splitting of the option lists is wanted
    after=$(sbatch --parsable $options ${after:+--dependency=afterok:$after} \
        --job-name="rrf-$stage" --array="0-$((shards - 1))" --output="rrf-$stage-%a.log" \
        --wrap="$rrf bake $scene --stage $stage --shard \$SLURM_ARRAY_TASK_ID/$shards $*")
    after=${after%%;*}
done
# shellcheck disable=SC2086
merge=$(sbatch --parsable $options --dependency=afterok:"$after" --job-name=rrf-merge --output=rrf-merge.log \
    --wrap="$rrf bake $scene --merge $*")
echo "${merge%%;*}"
