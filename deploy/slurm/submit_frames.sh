#!/bin/bash
# Renders views (one job description each) on a Slurm cluster, each split into regions:
#   1. prepare.sbatch        one job: every view's photon maps and irradiance cache, built once
#                            into the shared cache directory
#   2. render_region.sbatch  a job array, a region of a view per task, taking them from there
#   3. assemble.sbatch       joins each view's regions into OUT/<job name>.exr, byte for byte
#                            what `photond render` writes for the whole view
# Each step starts when the one before succeeded (--dependency=afterok) and is cancelled when it
# failed (--kill-on-invalid-dep=yes). The photond binary, the job files (and their scenes), the
# cache directory and OUT must be on a file system every node sees.
#
#   deploy/slurm/submit_frames.sh --photond /shared/bin/photond --cache-dir /shared/photond-cache \
#       --out /shared/frames --regions 2 2 [--wait] view1.json view2.json ...
#
# Job files give image.width and image.height. With --wait the script waits for the last step,
# prints the figures (wall time, the tasks' own times, the farm's overhead) and exits 1 if a step
# failed. Extra sbatch options (partition, account, time) go in SBATCH_* variables or
# PHOTOND_SBATCH_ARGS.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
usage() { echo "usage: $0 --photond PATH --cache-dir DIR --out DIR [--regions NX NY] [--wait] JOB.json..." >&2; exit 2; }
photond="" cache_dir="" out_dir="" nx=2 ny=2 wait=0 jobs=()
while [ $# -gt 0 ]; do
    case "$1" in
        --photond) photond=$(realpath "$2"); shift 2 ;;
        --cache-dir) mkdir -p "$2"; cache_dir=$(realpath "$2"); shift 2 ;;
        --out) mkdir -p "$2"; out_dir=$(realpath "$2"); shift 2 ;;
        --regions) nx=$2; ny=$3; shift 3 ;;
        --wait) wait=1; shift ;;
        -*) usage ;;
        *) jobs+=("$(realpath "$1")"); shift ;;
    esac
done
[ -n "$photond" ] && [ -n "$cache_dir" ] && [ -n "$out_dir" ] && [ ${#jobs[@]} -gt 0 ] || usage
[[ "$nx" =~ ^[1-9][0-9]*$ && "$ny" =~ ^[1-9][0-9]*$ ]] || { echo "$0: --regions wants two positive integers" >&2; exit 2; }

# The task table: a line per region, "JOB_FILE X0 Y0 X1 Y1 PART_EXR" (render_region.sbatch).
mkdir -p "$out_dir/parts" "$out_dir/logs"
tasks="$out_dir/tasks.txt"
: >"$tasks"
for job in "${jobs[@]}"; do
    [[ "$job" != *" "* ]] || { echo "$0: '$job': paths with spaces are not supported" >&2; exit 2; }
    size=$(python3 -c 'import json, sys
image = json.load(open(sys.argv[1])).get("image", {})
print(image["width"], image["height"])' "$job" 2>/dev/null) ||
        { echo "$0: $job: give image.width and image.height in the job" >&2; exit 2; }
    read -r width height <<<"$size"
    name=$(basename "$job" .json)
    for ((j = 0; j < ny; j++)); do
        for ((i = 0; i < nx; i++)); do
            echo "$job $((width * i / nx)) $((height * j / ny)) $((width * (i + 1) / nx)) $((height * (j + 1) / ny))" \
                "$out_dir/parts/${name}_$((j * nx + i)).exr" >>"$tasks"
        done
    done
done
count=$(wc -l <"$tasks")

export PHOTOND="$photond" CACHE_DIR="$cache_dir" OUT_DIR="$out_dir" TASKS="$tasks"
started=$(date +%s.%N)
# shellcheck disable=SC2086  # PHOTOND_SBATCH_ARGS holds several options
submit() { sbatch --parsable --export=ALL ${PHOTOND_SBATCH_ARGS:-} "$@" | cut -d';' -f1; }
prepare=$(submit -o "$out_dir/logs/prepare.txt" "$here/prepare.sbatch")
regions=$(submit --dependency="afterok:$prepare" --kill-on-invalid-dep=yes --array="0-$((count - 1))" \
    -o "$out_dir/logs/region-%a.txt" "$here/render_region.sbatch")
assemble=$(submit --dependency="afterok:$regions" --kill-on-invalid-dep=yes -o "$out_dir/logs/assemble.txt" \
    "$here/assemble.sbatch")
echo "submitted: prepare $prepare, regions $regions (${count} tasks), assemble $assemble"
[ "$wait" = 1 ] || exit 0

while [ -n "$(squeue -h -j "$prepare,$regions,$assemble" 2>/dev/null)" ]; do sleep 0.5; done
finished=$(date +%s.%N)
failed=0
for job in "${jobs[@]}"; do
    frame="$out_dir/$(basename "$job" .json).exr"
    [ -s "$frame" ] || { echo "$0: $frame was not made (logs: $out_dir/logs)" >&2; failed=1; }
done
[ "$failed" = 0 ] || exit 1
python3 - "$tasks" "$started" "$finished" <<'PY'
import json, sys
tasks, started, finished = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
renders = [json.load(open(line.split()[5][:-4] + ".json"))["total_seconds"] for line in open(tasks)]
wall = finished - started
print(f"{len(renders)} regions rendered in {sum(renders):.2f} s of task time (longest {max(renders):.2f} s); "
      f"submission to the last assembled frame {wall:.2f} s; farm overhead (that minus the region tasks' "
      f"own time, scheduling and the preparation included) {wall - sum(renders):.2f} s")
PY
