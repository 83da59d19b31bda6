#!/usr/bin/env bash
# Builds the tuning set: 40 MFCAD parts of the training split that the shipped model never saw
# (outside scripts/train-model.sh's SHA-1 subset), for choosing thresholds and post-processing
# options without touching the validation split.
#
#   scripts/make-tuning-set.sh [MFCAD_DIR] [OUT_DIR] [COUNT] [STRIDE]
#       (defaults: ../shared/data/mfcad out/mfcad_tune 40 97)
#
# Going through the pool's names in order, the meshes outside the subset, then every STRIDE-th
# of those in the train split, the first COUNT (paco_dataset --only-split train --stride STRIDE
# --limit COUNT). The larger tuning set of the twenty-fourth session:
#   scripts/make-tuning-set.sh ../shared/data/mfcad out/mfcad_tune160 160 23
set -euo pipefail
cd "$(dirname "$0")/.."
mfcad=${1:-../shared/data/mfcad}
out=${2:-out/mfcad_tune}
count=${3:-40}
stride=${4:-97}
if [ ! -d "$mfcad" ]; then
  echo "make-tuning-set.sh: '$mfcad' does not exist; pass the MFCAD folder as the first argument" >&2
  exit 1
fi
if [ ! -x build/apps/paco_dataset ]; then
  echo "make-tuning-set.sh: build paco_dataset first: cmake --build build -j2 --target paco_dataset" >&2
  exit 1
fi
outside=$(mktemp -d)
trap 'rm -rf "$outside"' EXIT
mfcad_abs=$(cd "$mfcad" && pwd)
for path in "$mfcad_abs"/*.obj; do
  name=$(basename "$path")
  hex=$(printf '%s' "$name" | sha1sum | cut -c1-40)
  sum=0
  # 16 = 1 (mod 3): a hex number is congruent to the sum of its digits, as in train-model.sh.
  for ((i = 0; i < 40; i++)); do sum=$((sum + 16#${hex:i:1})); done
  if [ $((sum % 3)) -ne 0 ]; then ln -s "$path" "$outside/$name"; fi
done
build/apps/paco_dataset "$outside" "$out" --only-split train --stride "$stride" --limit "$count" --jobs 2
