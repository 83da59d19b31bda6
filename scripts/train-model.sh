#!/usr/bin/env bash
# Builds the training set of the shipped model and trains it, or continues: the exact recipe of
# models/README.md. Everything goes under WORK_DIR; rerun the same command after an interruption
# (the dataset build and the training both resume).
#
#   scripts/train-model.sh WORK_DIR [--init-from MODEL.pt] [--epochs N] [--seed S] [--jitter J]
#                          [--orientation as-is|seen-planes] [--segment-min-points N]
#                          [--segment-min-parallel-points N] [--single-scanner-views N] [--run NAME]
#                          [-- PACO_TRAIN_OPTIONS...]
#
# --init-from starts a new run from a model's weights (e.g. models/paco_cpu.pt, to go on training
# the shipped model on a machine that kept nothing else); without it a new run starts from random
# weights. When WORK_DIR/run/last.pt exists the run is resumed and --init-from is ignored.
# --seed changes the training order and augmentation (not the data set); --jitter adds Gaussian
# noise to the training inputs (paco_train --augment-jitter); --orientation is paco_train's
# --input-orientation (default: the starting model's, else as-is); --run names the run folder
# under WORK_DIR (default: run). --segment-min-points is paco_dataset's: 0 (default) labels the
# inputs with planes as paco_reconstruct segments (1 % of their points, 0.25 % on an input without
# noise, as these are), into WORK_DIR/data;
# N > 0 uses planes of N points, into WORK_DIR/data_minN (the models up to the eleventh session's
# were trained on --segment-min-points 50). --segment-min-parallel-points is paco_dataset's too:
# N >= 0 also labels small planes parallel to a larger one (0: 0.15 % of the points, as the tools
# do by default), into a folder with the suffix _parN; the default, -1, labels none.
# --single-scanner-views N > 0 also trains on what one scanner sees from each of N viewpoints
# (paco_dataset --mode visibility --single-scanner, the part at the 25 % level, labelled the same
# way), built into WORK_DIR/data_1scan (with the same suffixes). Options
# after "--" go to paco_train as they are (e.g. --quality-classification --lr 5e-5
# --limit-train 16000); pass them again when resuming.
# Needs the MFCAD meshes in ../shared/data/mfcad (or MFCAD_DIR) and a Release build in build/.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -lt 1 ]; then
  sed -n '2,/^# Needs the MFCAD/p' "$0" >&2
  exit 2
fi
work=$1
shift
init_from=""
epochs=100
seed=1
jitter=0
orientation=""
run_name=run
segment_min_points=0
segment_min_parallel_points=-1
single_scanner_views=0
while [ $# -gt 0 ]; do
  case "$1" in
    --init-from) init_from=$2; shift 2 ;;
    --epochs) epochs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --jitter) jitter=$2; shift 2 ;;
    --orientation) orientation=$2; shift 2 ;;
    --run) run_name=$2; shift 2 ;;
    --segment-min-points) segment_min_points=$2; shift 2 ;;
    --segment-min-parallel-points) segment_min_parallel_points=$2; shift 2 ;;
    --single-scanner-views) single_scanner_views=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "train-model.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
mfcad=${MFCAD_DIR:-../shared/data/mfcad}
if [ ! -d "$mfcad" ]; then
  echo "train-model.sh: no MFCAD meshes in '$mfcad'; set MFCAD_DIR" >&2
  exit 1
fi
for tool in paco_dataset paco_train; do
  if [ ! -x "build/apps/$tool" ]; then
    echo "train-model.sh: build/apps/$tool is missing; build first:" >&2
    echo "  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build -j2 --target paco_dataset paco_train" >&2
    exit 1
  fi
done

# A third of the MFCAD pool: the meshes whose SHA-1(file name) is 0 mod 3. Since 16 = 1 (mod 3),
# a hex number is congruent to the sum of its digits.
subset="$work/mfcad_subset"
mkdir -p "$subset"
mfcad_abs=$(cd "$mfcad" && pwd)
for path in "$mfcad_abs"/*.obj; do
  name=$(basename "$path")
  [ -e "$subset/$name" ] && continue
  hex=$(printf '%s' "$name" | sha1sum | cut -c1-40)
  sum=0
  for ((i = 0; i < 40; i++)); do sum=$((sum + 16#${hex:i:1})); done
  if [ $((sum % 3)) -eq 0 ]; then ln -s "$path" "$subset/$name"; fi
done
echo "train-model.sh: $(ls "$subset" | wc -l) meshes in the training subset"

# Anisotropic scale 0.5-2 and rotation per part, 3 levels x 4 views, inputs labelled by GoCoPP
# (the segmenter the pipeline uses). About 5 min on 2 cores.
suffix=""
if [ "$segment_min_points" != 0 ]; then suffix="_min$segment_min_points"; fi
if [ "$segment_min_parallel_points" -ge 0 ]; then suffix="${suffix}_par$segment_min_parallel_points"; fi
labels=(--segment --segment-min-points "$segment_min_points" --segment-min-parallel-points "$segment_min_parallel_points")
data="$work/data$suffix"
build/apps/paco_dataset "$subset" "$data" --augment-scale 0.5,2 --augment-rotate "${labels[@]}" \
  --views 4 --jobs 2 --seed 1
datasets=("$data")
# One scanner's view of each part, level 0 only (a single scanner hides 45-66 % of an MFCAD part,
# so the 25 % level keeps all it sees). About 4 min on 2 cores for 4 views.
if [ "$single_scanner_views" -gt 0 ]; then
  single="$work/data_1scan$suffix"
  build/apps/paco_dataset "$subset" "$single" --mode visibility --single-scanner --levels 0 \
    --views "$single_scanner_views" --augment-scale 0.5,2 --augment-rotate "${labels[@]}" --jobs 2 --seed 1
  datasets+=("$single")
fi

run="$work/$run_name"
args=("${datasets[@]}" -o "$run" --preset cpu --input-frame own --augment-scale 0.2 --augment-offset 0.05
      --augment-jitter "$jitter" --limit-val 480 --epochs "$epochs" --threads 2 --seed "$seed" --checkpoint-every 100)
if [ -n "$orientation" ]; then
  args+=(--input-orientation "$orientation")
fi
args+=("$@")
if [ -e "$run/last.pt" ]; then
  args+=(--resume)
elif [ -n "$init_from" ]; then
  args+=(--init-from "$init_from")
fi
exec build/apps/paco_train "${args[@]}"
