#!/usr/bin/env bash
# Installs what is missing, builds everything (library, tools, tests, benchmarks) and runs the
# whole test suite with ctest. This is the README's test command and what CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
start=$(date +%s)
cmake --build build -j"$jobs"
echo "paco: build took $(( $(date +%s) - start )) s"
cd build
ctest -j"$jobs" --output-on-failure --timeout 600
