#!/usr/bin/env bash
# Camera refinement on real SfM cameras (issue #11): Middlebury's
# templeSparseRing (or dinoSparseRing) through scripts/colmap_pipeline.sh (COLMAP's
# own CPU SfM, so the cameras are COLMAP's, and the visual hull of the masks),
# with every 4th image held out, refined without and with
# --Refine.refine_cameras. Reports:
#   - held-out photo-consistency (mean ZNCC of the held-out images against
#     their neighbours through the mesh) before and after refinement, with
#     the held-out images at their SfM poses and registered to the refined
#     model (mesh_refiner prints both);
#   - how far COLMAP's cameras, and the refined ones, are from the data set's
#     calibration (*_par.txt), after aligning each model to it with a
#     similarity (colmap model_aligner on the camera centres): the RMS
#     reprojection displacement of the calibrated visual hull's vertices
#     (mesh_evaluator --sparse_path/--true_sparse_path).
#
#   bash benchmark/refine/run_temple_sfm.sh OUT_DIR [templeSparseRing|dinoSparseRing]
#
# CONFIGS: "label|mesh_refiner flags" per line (default none, poses). BIN:
# another build's bin/.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: run_temple_sfm.sh OUT_DIR [data set]}
SET=${2:-templeSparseRing}
OUT=$(realpath -m "$OUT")
BIN=${BIN:-$PWD/build/bin}
DATA=$(realpath "../shared/data/middlebury/$SET")
CONFIGS=${CONFIGS:-"none|--Refine.refine_cameras none
poses|--Refine.refine_cameras poses"}
export QT_QPA_PLATFORM=offscreen
mkdir -p "$OUT"
par="$OUT/par"        # the calibrated workspace (masks, holdout.txt, PINHOLE model)
project="$OUT/project"

if [ ! -f "$par/meshed-visualhull.ply" ]; then
  rm -rf "$par"
  "$BIN/middlebury_to_colmap" --input_path "$DATA" --output_path "$par" > "$OUT/par.log" 2>&1
  "$BIN/mesh_initializer" --workspace_path "$par" --use_holdout 0 >> "$OUT/par.log" 2>&1
fi
holdout="$OUT/holdout.txt"
grep -v '^#' "$par/holdout.txt" > "$holdout"
# SfM and the visual hull only (the refinement is run per configuration below).
if [ ! -f "$project/meshed-visualhull.ply" ]; then
  bash scripts/colmap_pipeline.sh --image_path "$DATA" --mask_path "$par/masks" \
    --output_path "$project" --single_camera 1 --bin "$BIN" -- --dry_run 1 \
    > "$OUT/pipeline.log" 2>&1
  rm -f "$project/meshed-refined.ply"
fi
undistorted="$project/mesh_refiner_undistorted"

# Camera centres of the calibrated model, for model_aligner (name X Y Z).
mkdir -p "$OUT/par_txt"
colmap model_converter --input_path "$par/sparse" --output_path "$OUT/par_txt" \
  --output_type TXT > /dev/null 2>&1
python3 - "$OUT/par_txt/images.txt" > "$OUT/ref_centres.txt" <<'EOF'
import sys
lines = [l for l in open(sys.argv[1]) if not l.startswith('#')]
for l in lines[0::2]:
    f = l.split()
    if len(f) < 10:
        continue
    qw, qx, qy, qz, tx, ty, tz = map(float, f[1:8])
    R = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
         [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
         [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]]
    C = [-(R[0][i] * tx + R[1][i] * ty + R[2][i] * tz) for i in range(3)]
    print(f[9], *C)
EOF

# align MODEL_DIR NAME: the model in the calibrated frame, compared with it.
align() {
  rm -rf "$OUT/aligned_$2"
  mkdir -p "$OUT/aligned_$2"
  colmap model_aligner --input_path "$1" --output_path "$OUT/aligned_$2" \
    --ref_images_path "$OUT/ref_centres.txt" --ref_is_gps 0 --alignment_type custom \
    --robust_alignment 1 --robust_alignment_max_error 5 > "$OUT/aligned_$2.log" 2>&1
  "$BIN/mesh_evaluator" --input_path "$par/meshed-visualhull.ply" \
    --gt_path "$par/meshed-visualhull.ply" --num_samples 1000 --sparse_path "$OUT/aligned_$2" \
    --true_sparse_path "$par/sparse" 2> /dev/null
}

printf '| run | mean similarity (all views used) | held-out photo-consistency, SfM poses | the same, held-out views registered | cameras vs calibration, RMS (worst image) px | time s |\n|---|---|---|---|---|---|\n' \
  > "$OUT/results.md"
sfm=$(align "$undistorted/sparse" sfm)
python3 - "$sfm" >> "$OUT/results.md" <<'EOF'
import json, sys
m = json.loads(sys.argv[1])
print(f"| COLMAP SfM cameras, visual hull | | | | {m['camera_rms_px']:.3f} ({m['camera_max_rms_px']:.3f}) | |")
EOF
while IFS= read -r config; do
  [ -z "$config" ] && continue
  label=${config%%|*}
  flags=${config#*|}
  out="$project/meshed-refined-$label.ply"
  if [ ! -f "$out" ]; then
    rm -rf "$undistorted/sparse_refined"
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e" -o "$OUT/$label.time" "$BIN/mesh_refiner" --workspace_path "$project" \
      --input_path "$project/meshed-visualhull.ply" --output_path "$out" \
      --holdout_path "$holdout" $flags > "$OUT/$label.log" 2>&1
    if [ -d "$undistorted/sparse_refined" ]; then
      rm -rf "$OUT/sparse_refined_$label"
      mv "$undistorted/sparse_refined" "$OUT/sparse_refined_$label"
    fi
  fi
  cameras="$undistorted/sparse"
  [ -d "$OUT/sparse_refined_$label" ] && cameras="$OUT/sparse_refined_$label"
  json=$(align "$cameras" "$label")
  similarity=$(grep -o "mean similarity [-0-9.]* -> [-0-9.]*" "$OUT/$label.log" | tail -1 | cut -d' ' -f3-)
  heldout=$(grep -o "Held-out photo-consistency (mean.*" "$OUT/$label.log" | tail -1 | sed 's/.*: //')
  registered=$(grep -o "Held-out photo-consistency with.*" "$OUT/$label.log" | tail -1 | sed 's/.*: //')
  python3 - "$json" "$label" "$similarity" "$heldout" "$(cat "$OUT/$label.time")" "$registered" >> "$OUT/results.md" <<'EOF'
import json, sys
m = json.loads(sys.argv[1])
print(f"| mesh_refiner {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {sys.argv[6]} | "
      f"{m['camera_rms_px']:.3f} ({m['camera_max_rms_px']:.3f}) | {float(sys.argv[5]):.0f} |")
EOF
done <<< "$CONFIGS"
cat "$OUT/results.md"
