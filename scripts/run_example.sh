#!/usr/bin/env bash
# Installs missing packages, builds, makes the bundled example workspace from
# the built-in shape (no ../shared needed), refines its COLMAP Poisson mesh
# and compares both meshes with the ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
export QT_QPA_PLATFORM=offscreen
EXAMPLE=workspace_examples/builtin
if [ ! -f "$EXAMPLE/dense/meshed-poisson.ply" ]; then
  rm -rf "$EXAMPLE"
  build/bin/workspace_synthesizer --output_path "$EXAMPLE"
fi
build/bin/mesh_refiner --workspace_path "$EXAMPLE/dense"
echo
# Figures over the surface the cameras observe (Middlebury-style).
echo "Initial mesh (COLMAP poisson_mesher) vs ground truth:"
build/bin/mesh_evaluator --input_path "$EXAMPLE/dense/meshed-poisson.ply" \
  --gt_path "$EXAMPLE/ground_truth.ply" --workspace_path "$EXAMPLE/dense"
echo "Refined mesh (mesh_refiner) vs ground truth:"
build/bin/mesh_evaluator --input_path "$EXAMPLE/dense/meshed-refined.ply" \
  --gt_path "$EXAMPLE/ground_truth.ply" --workspace_path "$EXAMPLE/dense"
echo
echo "Refined mesh: $EXAMPLE/dense/meshed-refined.ply"
