#!/usr/bin/env bash
# One item of an anm sweep per Slurm array task (docs/cluster.md).
#
#   n=$(anm audit SCENE --eta 1e-8,1e-6,1e-4 --list-items | wc -l)
#   jid=$(sbatch --parsable --array=0-$((n - 1)) docs/slurm-sweep.sh OUT \
#         anm audit SCENE --eta 1e-8,1e-6,1e-4)
#   sbatch --dependency=afterok:$jid --wrap "anm merge OUT"
#
# Arguments: the output folder shared by all tasks (OUT/items/K.json), then
# the sweep command as for a single-process run, without -o. The --array
# range given to sbatch overrides the one below.
#SBATCH --job-name=anm-sweep
#SBATCH --array=0-10
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --output=anm-sweep-%A_%a.out
set -euo pipefail
if [ "$#" -lt 2 ]; then
    echo "usage: sbatch --array=0-N $0 OUT anm audit|stress|bench ... (without -o)" >&2
    exit 64
fi
out=$1
shift
task=${SLURM_ARRAY_TASK_ID:?"not an array task: submit with sbatch --array=0-N"}
exec "$@" --item "$task" -o "$out"
