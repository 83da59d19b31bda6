#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, and runs the main job: the whole
# pipeline (segment, complete, assemble) on the sample partial scan that the project ships
# (data/sample_partial.pcd, made by paco_dataset; see data/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target paco_reconstruct
mkdir -p out
input=data/sample_partial.pcd
if ls models/*.pt > /dev/null 2>&1; then
  ./build/apps/paco_reconstruct "$input" -o out/sample_mesh.obj
else
  # No trained model is shipped yet (see models/README.md): run the pipeline without the learned
  # completion, i.e. the paper's "direct" baseline, which shows what completion has to fix.
  echo "paco: no trained model in models/ yet; running without completion (--no-completion)"
  ./build/apps/paco_reconstruct "$input" -o out/sample_mesh.obj --no-completion
fi
echo "paco: the mesh is in out/sample_mesh.obj (primitives: out/sample_mesh.vg, out/sample_mesh_primitives.pcd)"
