#!/usr/bin/env bash
# Camera refinement (--Refine.refine_cameras) on corpus workspaces whose
# sparse model carries SfM-like camera error (issue #11). For each case and
# error level: workspace_synthesizer with the case's corpus flags plus
# --CameraError.* (the images and depth maps stay true; COLMAP fuses and
# meshes with the wrong cameras; the true model goes to <ws>/sparse_true),
# then mesh_refiner without and with camera refinement, then mesh_evaluator
# on the observed surface and on the cameras (the refined model, or the input
# one without refinement, against the true one: RMS reprojection displacement
# of the ground-truth vertices each true view sees), once as they are and once
# datum-aligned (mesh_evaluator --align_cameras: mesh and cameras carried into
# the true world by the similarity that best aligns the cameras, the gauge
# that independent pose errors move and no refinement can know). Prints a markdown table
# (benchmark/refine/camera_table.py). Results in OUT_DIR are reused.
#
#   bash benchmark/refine/run_cameras.sh OUT_DIR [case ...]
#
# Cases default to four of benchmark/refine/corpus.txt with 12-16 views and
# four image styles; LEVELS and CONFIGS replace the error levels and the
# refiner configurations ("label|flags" per line). BIN points at another
# build's bin/.
set -euo pipefail
cd "$(dirname "$0")/../.."
# shellcheck source=benchmark/refine/corpus_lib.sh
source benchmark/refine/corpus_lib.sh

cases="builtin-contrast fandisk-shading rocker-head-noise homer-color-small"
if [ $# -gt 0 ]; then cases="$*"; fi
LEVELS=${LEVELS:-"exact|
pose0.5|--CameraError.pose_error_px 0.5
pose1|--CameraError.pose_error_px 1
pose2|--CameraError.pose_error_px 2
pose1+focal0.5|--CameraError.pose_error_px 1 --CameraError.focal_error_percent 0.5"}
CONFIGS=${CONFIGS:-"none|--Refine.refine_cameras none
poses|--Refine.refine_cameras poses
poses_intrinsics|--Refine.refine_cameras poses_intrinsics"}
# poses_intrinsics only where the focal length is wrong, and on exact cameras.
wanted() { [ "$2" != poses_intrinsics ] || [ "$1" = exact ] || [[ "$1" == *focal* ]]; }

TSV="$OUT/results.tsv"
: > "$TSV"
for name in $cases; do
  flags=$(case_flags "$name")
  while IFS= read -r level; do
    [ -z "$level" ] && continue
    lname=${level%%|*}
    lflags=${level#*|}
    ws="$OUT/$name-$lname"
    if [ ! -f "$ws/dense/meshed-poisson.ply" ]; then
      rm -rf "$ws"
      echo "[$(date +%T)] synthesising $name ($lname)" >&2
      # shellcheck disable=SC2086
      "$BIN/workspace_synthesizer" --output_path "$ws" $flags $lflags > "$ws.synth.log" 2>&1
    fi
    truth="$ws/sparse_true"
    [ -d "$truth" ] || truth="$ws/dense/sparse"
    evaluate() {  # mesh cameras stem: STEM.json as it is, STEM.aligned.json datum-aligned
      for variant in "json 0" "aligned.json 1"; do
        set -- "$1" "$2" "$3" $variant
        [ -f "$3.$4" ] && continue
        "$BIN/mesh_evaluator" --input_path "$1" --gt_path "$ws/ground_truth.ply" \
          --workspace_path "$ws/dense" --sparse_path "$2" --true_sparse_path "$truth" \
          --align_cameras "$5" > "$3.$4"
      done
    }
    evaluate "$ws/dense/meshed-poisson.ply" "$ws/dense/sparse" "$ws.input"
    printf '%s\t%s\tinput\t%s\t%s\t0\t0\n' "$name" "$lname" "$(cat "$ws.input.json")" \
      "$(cat "$ws.input.aligned.json")" >> "$TSV"
    while IFS= read -r config; do
      [ -z "$config" ] && continue
      label=${config%%|*}
      rflags=${config#*|}
      wanted "$lname" "$label" || continue
      stem="$ws.$label"
      if [ ! -s "$stem.time" ] || [ ! -f "$ws/dense/meshed-refined-$label.ply" ]; then
        echo "[$(date +%T)] $name ($lname): $label" >&2
        rm -rf "$ws/dense/sparse_refined"
        # shellcheck disable=SC2086
        /usr/bin/time -f "%e %M" -o "$stem.time" "$BIN/mesh_refiner" --workspace_path "$ws/dense" \
          --output_path "$ws/dense/meshed-refined-$label.ply" $rflags > "$stem.log" 2>&1 || {
            rm -f "$stem.time"
            echo "mesh_refiner failed on $name ($lname, $label): see $stem.log" >&2; continue; }
        rm -rf "$ws/dense/sparse_refined-$label" "$stem.json" "$stem.aligned.json"
        if [ -d "$ws/dense/sparse_refined" ]; then
          mv "$ws/dense/sparse_refined" "$ws/dense/sparse_refined-$label"
        fi
      fi
      cameras="$ws/dense/sparse_refined-$label"
      [ -d "$cameras" ] || cameras="$ws/dense/sparse"
      evaluate "$ws/dense/meshed-refined-$label.ply" "$cameras" "$stem"
      read -r secs kb < "$stem.time"
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$lname" "$label" "$(cat "$stem.json")" \
        "$(cat "$stem.aligned.json")" "$secs" "$((kb / 1024))" >> "$TSV"
    done <<< "$CONFIGS"
  done <<< "$LEVELS"
done
python3 benchmark/refine/camera_table.py "$TSV" | tee "$OUT/results.md"
