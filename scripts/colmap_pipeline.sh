#!/usr/bin/env bash
# From photographs to a refined mesh: COLMAP's structure-from-motion, then an
# initial surface, then mesh_refiner.
#
#   scripts/colmap_pipeline.sh --image_path photos/ --output_path project/
#       [--mask_path masks/] [--single_camera 1] [--colmap colmap]
#       [--bin build/bin] [-- mesh_refiner options ...]
#
# Stages (each is skipped when its output exists, so an interrupted run is
# resumed by running the same command again; delete a stage's output to redo
# it):
#   1. features   colmap feature_extractor + exhaustive_matcher -> project/database.db
#                 (GPU SIFT when COLMAP has CUDA, CPU SIFT otherwise)
#   2. sfm        colmap mapper -> project/sparse/0 (the model with most
#                 registered images); if the defaults leave images out (wide
#                 baselines, few matches, as on object rings), once more with a
#                 lenient initialisation, keeping the better; the log says so
#   3. surface    with CUDA: colmap image_undistorter, patch_match_stereo,
#                 stereo_fusion, poisson_mesher -> project/dense/meshed-poisson.ply
#                 without CUDA: the visual hull of the masks (--mask_path,
#                 COLMAP's convention: <image name>.png, non-zero = object):
#                 mesh_initializer on the sparse project, which undistorts the
#                 images and masks together (COLMAP's image_undistorter does
#                 not undistort masks) -> project/meshed-visualhull.ply
#   4. refine     mesh_refiner -> project/dense/meshed-refined.ply (CUDA route)
#                 or project/meshed-refined.ply (visual-hull route)
# Options after "--" go to mesh_refiner. Exit status: that of the first
# stage that failed (its log is named), 2 for bad arguments.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

usage() { sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
log() { echo "colmap_pipeline: $*"; }
die() { echo "colmap_pipeline: ERROR: $*" >&2; exit "${2:-2}"; }

image_path="" output_path="" mask_path="" single_camera=0 colmap=colmap
bin="$here/../build/bin"
refiner_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --image_path) image_path=${2:?}; shift 2 ;;
    --output_path) output_path=${2:?}; shift 2 ;;
    --mask_path) mask_path=${2:?}; shift 2 ;;
    --single_camera) single_camera=${2:?}; shift 2 ;;
    --colmap) colmap=${2:?}; shift 2 ;;
    --bin) bin=${2:?}; shift 2 ;;
    -h|--help) usage ;;
    --) shift; refiner_args=("$@"); break ;;
    *) echo "colmap_pipeline: unknown argument $1" >&2; usage ;;
  esac
done
[ -n "$image_path" ] && [ -n "$output_path" ] || usage
[ -d "$image_path" ] || die "--image_path $image_path: not a folder"
[ -z "$mask_path" ] || [ -d "$mask_path" ] || die "--mask_path $mask_path: not a folder"
case "$single_camera" in 0|1) ;; *) die "--single_camera $single_camera: expected 0 or 1" ;; esac
command -v "$colmap" > /dev/null || die "COLMAP not found as '$colmap' (install it: apt-get install colmap, or pass --colmap PATH)"
for tool in mesh_initializer mesh_refiner; do
  [ -x "$bin/$tool" ] || die "$bin/$tool not found: build the project first (bash scripts/build.sh) or pass --bin"
done
image_path=$(realpath "$image_path")
[ -z "$mask_path" ] || mask_path=$(realpath "$mask_path")
output_path=$(realpath -m "$output_path")
case "$output_path/" in "$image_path/"*) die "--output_path may not be inside --image_path" ;; esac
export QT_QPA_PLATFORM=offscreen

# run NAME command...: the command's output goes to logs/NAME.log.
run() {
  local name=$1; shift
  log "  $name: $*" | cut -c1-300
  local rc=0
  "$@" > "$logs/$name.log" 2>&1 || rc=$?
  if [ "$rc" != 0 ]; then
    tail -n 5 "$logs/$name.log" | sed 's/^/    /' >&2
    die "$name failed (exit $rc); see $logs/$name.log" "$rc"
  fi
}

help_text=$("$colmap" -h 2>&1 || true)
version=${help_text%%$'\n'*}
cuda=0
case "$help_text" in *"with CUDA"*) cuda=1 ;; esac
log "COLMAP: $(command -v "$colmap"): $version"
if [ "$cuda" = 1 ]; then
  log "route: COLMAP has CUDA: GPU SIFT, dense stereo, fusion and Poisson, then mesh_refiner"
  gpu=1
elif [ -n "$mask_path" ]; then
  log "route: COLMAP has no CUDA: CPU SIFT, and the visual hull of $mask_path as the initial surface (no dense stereo without CUDA), then mesh_refiner"
  gpu=0
else
  die "COLMAP here has no CUDA, so it cannot compute depth maps (patch_match_stereo); give --mask_path (COLMAP's convention: <image name>.png, non-zero = object) to start from the visual hull"
fi
mkdir -p "$output_path" || die "cannot create --output_path $output_path"
logs="$output_path/logs"
mkdir -p "$logs"

# 1. Features and matches.
db="$output_path/database.db"
if [ -f "$output_path/.matches_done" ]; then
  log "1. features: $db exists, skipped"
else
  log "1. features and matches -> $db"
  rm -f "$db"
  run feature_extractor "$colmap" feature_extractor --database_path "$db" --image_path "$image_path" \
    --ImageReader.single_camera "$single_camera" --SiftExtraction.use_gpu "$gpu"
  run exhaustive_matcher "$colmap" exhaustive_matcher --database_path "$db" \
    --SiftMatching.use_gpu "$gpu"
  touch "$output_path/.matches_done"
fi

# 2. Structure from motion.
sparse="$output_path/sparse/0"
if [ -f "$sparse/images.bin" ] || [ -f "$sparse/images.txt" ]; then
  log "2. sfm: $sparse exists, skipped"
else
  log "2. sfm -> $sparse"
  scratch="$output_path/.mapper"
  rm -rf "$scratch"
  mkdir -p "$scratch/default" "$scratch/lenient"
  processed=$(grep -c "Processed file" "$logs/feature_extractor.log" || true)
  unreadable=$(grep -c "Failed to read image" "$logs/feature_extractor.log" || true)
  num_images=$((processed - unreadable))
  # consider DIR...: keeps in best the model folder with the most registered images.
  best="" best_count=0
  consider() {
    local model count analysis
    for model in "$@"; do
      [ -f "$model/images.bin" ] || continue
      # The analyzer's whole output first: under pipefail, a reader that
      # stops early (grep -m1, head) fails the pipeline with SIGPIPE.
      analysis=$("$colmap" model_analyzer --path "$model" 2>&1 || true)
      count=0
      if [[ $analysis =~ Registered\ images:\ ([0-9]+) ]]; then count=${BASH_REMATCH[1]}; fi
      if [ "$count" -gt "$best_count" ]; then best=$model best_count=$count; fi
    done
  }
  # The defaults may fail outright ("failed to create sparse model"): that
  # counts as no image registered, and the lenient run below decides.
  log "  mapper: $colmap mapper --database_path $db --image_path $image_path --output_path $scratch/default"
  if ! "$colmap" mapper --database_path "$db" --image_path "$image_path" \
      --output_path "$scratch/default" > "$logs/mapper.log" 2>&1; then
    log "  mapper failed with its defaults ($(grep -m1 -o 'ERROR.*' "$logs/mapper.log" || echo "see $logs/mapper.log"))"
  fi
  consider "$scratch"/default/*/
  if [ "$best_count" -lt "$num_images" ]; then
    log "  mapper registered $best_count of $num_images images with its defaults; again with a lenient initialisation (init_min_tri_angle 4, init_min_num_inliers 50, abs_pose_min_num_inliers 15)"
    run mapper_lenient "$colmap" mapper --database_path "$db" --image_path "$image_path" \
      --output_path "$scratch/lenient" --Mapper.init_min_tri_angle 4 \
      --Mapper.init_min_num_inliers 50 --Mapper.abs_pose_min_num_inliers 15
    consider "$scratch"/lenient/*/
  fi
  [ -n "$best" ] || die "mapper registered no model; see $logs/mapper*.log" 1
  log "  kept $best ($best_count of $num_images images)"
  mkdir -p "$output_path/sparse"
  mv "$best" "$sparse"
  rm -rf "$scratch"
fi
"$colmap" model_analyzer --path "$sparse" > "$logs/model_analyzer.log" 2>&1 || true
registered=$(grep -m1 -o "Registered images: [0-9]*" "$logs/model_analyzer.log" || true)
reprojection=$(grep -m1 -o "Mean reprojection error: [0-9.]*px" "$logs/model_analyzer.log" || true)
log "  model: ${registered:-?}, ${reprojection:-?}"

# 3. Initial surface, and 4. refinement.
if [ "$cuda" = 1 ]; then
  dense="$output_path/dense"
  if [ -f "$dense/meshed-poisson.ply" ]; then
    log "3. surface: $dense/meshed-poisson.ply exists, skipped"
  else
    log "3. surface: undistortion, dense stereo, fusion, Poisson -> $dense/meshed-poisson.ply"
    if [ ! -f "$dense/sparse/images.bin" ]; then
      run image_undistorter "$colmap" image_undistorter --image_path "$image_path" \
        --input_path "$sparse" --output_path "$dense" --output_type COLMAP
    fi
    run patch_match_stereo "$colmap" patch_match_stereo --workspace_path "$dense" \
      --PatchMatchStereo.geom_consistency true
    run stereo_fusion "$colmap" stereo_fusion --workspace_path "$dense" \
      --output_path "$dense/fused.ply"
    run poisson_mesher "$colmap" poisson_mesher --input_path "$dense/fused.ply" \
      --output_path "$dense/meshed-poisson.ply"
  fi
  workspace=$dense
  initial="$dense/meshed-poisson.ply"
else
  # The sparse project (images/, masks/, sparse/0/) that mesh_initializer and
  # mesh_refiner undistort; images and masks are linked, not copied.
  for pair in "images:$image_path" "masks:$mask_path"; do
    link="$output_path/${pair%%:*}" target=${pair#*:}
    if [ -L "$link" ]; then
      [ "$(readlink "$link")" = "$target" ] || die "$link links to $(readlink "$link"), not $target; remove it"
    elif [ -e "$link" ]; then
      die "$link exists and is not the link to $target this script makes; move it away"
    else
      ln -s "$target" "$link"
    fi
  done
  workspace=$output_path
  initial="$output_path/meshed-visualhull.ply"
  if [ -f "$initial" ]; then
    log "3. surface: $initial exists, skipped"
  else
    log "3. surface: visual hull of the masks -> $initial"
    run mesh_initializer "$bin/mesh_initializer" --workspace_path "$workspace" \
      --output_path "$initial"
  fi
fi

refined="$workspace/meshed-refined.ply"
if [ -f "$refined" ]; then
  log "4. refine: $refined exists, skipped"
else
  log "4. refine -> $refined (log: $logs/mesh_refiner.log)"
  run mesh_refiner "$bin/mesh_refiner" --workspace_path "$workspace" --input_path "$initial" \
    --output_path "$refined" "${refiner_args[@]}"
  grep -E "similarity|FINISHED|time:" "$logs/mesh_refiner.log" | tail -n 4 | sed 's/^/    /' || true
fi
log "done: $refined"
