#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, and runs the main job on the
# sample partial scan that the project ships (data/sample_partial.pcd).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPACO_BUILD_TESTS=OFF -DPACO_BUILD_BENCHMARKS=OFF
cmake --build build -j"$(nproc)"
mkdir -p out
input=data/sample_partial.pcd
./build/apps/paco_convert "$input" out/sample_normalized.pcd --normalize
echo "paco: wrote out/sample_normalized.pcd"
