#!/usr/bin/env bash
# Accuracy of mesh_refiner on synthetic COLMAP workspaces with ground truth.
# For each scene: workspace_synthesizer (real colmap stereo_fusion +
# poisson_mesher), then mesh_refiner with the paper's method (dcv + lp, the
# defaults) and the isotropic baseline (zncc + laplacian), then
# mesh_evaluator on the Poisson mesh and both results. The figures cover the
# observed surface (ground-truth faces seen by >= 2 cameras, as Middlebury
# evaluates); accuracy90 over the whole surface is given too. Wall time and
# peak memory of each refinement come from /usr/bin/time. Existing results in
# OUT_DIR are reused (delete a scene's folder to redo it).
#
#   bash benchmark/refine/run_synthetic.sh OUT_DIR [scene ...]
#   scenes: builtin bunny fandisk rocker-arm (default: all)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: run_synthetic.sh OUT_DIR [scene ...]}
shift || true
SCENES=${*:-builtin bunny fandisk rocker-arm}
BIN=build/bin
SHARED=../shared/data/models
export QT_QPA_PLATFORM=offscreen
mkdir -p "$OUT"
RESULTS="$OUT/results.md"
echo "| scene | mesh | faces | accuracy90 | completeness % | chamfer | normal_deg | accuracy90 (whole surface) | refine s | peak MB |" > "$RESULTS"
echo "|---|---|---|---|---|---|---|---|---|---|" >> "$RESULTS"

row() {  # scene label mesh seconds mb
  local observed whole
  observed=$("$BIN/mesh_evaluator" --input_path "$3" --gt_path "$OUT/$1/ground_truth.ply" \
    --workspace_path "$OUT/$1/dense")
  whole=$("$BIN/mesh_evaluator" --input_path "$3" --gt_path "$OUT/$1/ground_truth.ply")
  python3 - "$1" "$2" "$observed" "$whole" "$4" "$5" >> "$RESULTS" <<'PY'
import json, sys
scene, label, o, w, secs, mb = sys.argv[1:]
r, a = json.loads(o), json.loads(w)
print(f"| {scene} | {label} | {r['faces']} | {r['accuracy90']:.4f} | {r['completeness']:.2f} | "
      f"{r['chamfer']:.4f} | {r['normal_deg']:.2f} | {a['accuracy90']:.4f} | {secs} | {mb} |")
PY
}

for scene in $SCENES; do
  ws="$OUT/$scene"
  if [ ! -f "$ws/dense/meshed-poisson.ply" ]; then
    rm -rf "$ws"
    case "$scene" in
      builtin) "$BIN/workspace_synthesizer" --output_path "$ws" ;;
      bunny) "$BIN/workspace_synthesizer" --output_path "$ws" --model_path "$SHARED/stanford-bunny.obj" --model_up_axis y ;;
      *) "$BIN/workspace_synthesizer" --output_path "$ws" --model_path "$SHARED/$scene.obj" ;;
    esac > "$OUT/$scene.synth.log" 2>&1
  fi
  row "$scene" "COLMAP Poisson (input)" "$ws/dense/meshed-poisson.ply" "" ""
  for config in "dcv+lp:--Refine.similarity dcv --Refine.regularizer lp" \
                "zncc+laplacian:--Refine.similarity zncc --Refine.regularizer laplacian --Refine.open_border_rings 0"; do
    label=${config%%:*}
    flags=${config#*:}
    out="$ws/dense/meshed-refined-${label/+/-}.ply"
    if [ ! -f "$out" ] || [ ! -f "$OUT/$scene.$label.time" ]; then
      /usr/bin/time -f "%e %M" -o "$OUT/$scene.$label.time" \
        "$BIN/mesh_refiner" --workspace_path "$ws/dense" --output_path "$out" $flags \
        > "$OUT/$scene.$label.log" 2>&1
    fi
    read -r secs kb < "$OUT/$scene.$label.time"
    row "$scene" "$label" "$out" "$secs" "$((kb / 1024))"
  done
done
cat "$RESULTS"
