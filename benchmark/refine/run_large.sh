#!/usr/bin/env bash
# Real-size workspaces (issue #10): mesh_refiner with its defaults on
#   a) 40 views of 1920x1440, COLMAP's Poisson mesh of the built-in shape;
#   b) 100 views of 1600x1200;
#   c) the example's 16 views of 640x480 with an input mesh of about 2M
#      faces (COLMAP's Poisson mesh remeshed to 0.7-pixel edges by
#      mesh_refiner itself, with no iterations: Poisson at depth 10 gives only
#      365k faces from the example's 84k fused points);
#   d) 12 views of 6000x4000 (24 MP, rendered without supersampling; COLMAP
#      fuses their depth maps at 2000 px, the full-size fusion of 12 x 24 MP
#      being what a real pipeline would run at its own max_image_size);
# each made by workspace_synthesizer (real colmap fusion + Poisson), timed
# with /usr/bin/time (wall seconds, peak KB) and evaluated on the observed
# surface. One line per case: the refiner's working resolution and faces,
# time, memory, accuracy90 and normal error before and after. Workspaces
# and results in OUT_DIR are reused.
#
#   bash benchmark/refine/run_large.sh OUT_DIR [a b c d]
#
# REFINER_FLAGS adds flags to every refinement (default: none).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=$(realpath -m "${1:?usage: $(basename "$0") OUT_DIR [a b c d]}")
shift
cases=${*:-a b c d}
BIN=${BIN:-$PWD/build/bin}
export QT_QPA_PLATFORM=offscreen
mkdir -p "$OUT"

synth_flags() {
  case $1 in
    a) echo "--num_views 40 --width 1920 --height 1440" ;;
    b) echo "--num_views 100 --width 1600 --height 1200 --layout hemisphere" ;;
    c) echo "--num_views 16" ;;
    d) echo "--num_views 12 --width 6000 --height 4000 --supersample 1 --StereoFusion.max_image_size 2000" ;;
    *) echo "unknown case: $1 (a, b, c or d)" >&2; exit 2 ;;
  esac
}

json_field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$@"; }

{
printf '| case | workspace | working size, faces | wall s | peak MB | accuracy90 in -> out | normal_deg in -> out |\n'
printf '|---|---|---|---|---|---|---|\n'
for c in $cases; do
  flags=$(synth_flags "$c")
  ws="$OUT/$c"
  if [ ! -f "$ws/dense/meshed-poisson.ply" ]; then
    rm -rf "$ws"
    echo "[$(date +%T)] synthesising $c: $flags" >&2
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e %M" -o "$OUT/$c.synth.time" "$BIN/workspace_synthesizer" \
      --output_path "$ws" $flags > "$OUT/$c.synth.log" 2>&1
  fi
  evaluate() {
    "$BIN/mesh_evaluator" --input_path "$1" --gt_path "$ws/ground_truth.ply" \
      --workspace_path "$ws/dense"
  }
  input="$ws/dense/meshed-poisson.ply"
  if [ "$c" = c ]; then
    input="$ws/dense/meshed-2m.ply"
    if [ ! -f "$input" ]; then
      echo "[$(date +%T)] remeshing c's Poisson mesh to about 2M faces" >&2
      "$BIN/mesh_refiner" --workspace_path "$ws/dense" --output_path "$input" \
        --Refine.iterations_per_level 0 --Refine.num_levels 1 --Refine.target_edge_px 0.7 \
        --Refine.max_faces 2200000 --Refine.output_subdivisions 0 > "$OUT/$c.remesh.log" 2>&1
    fi
  fi
  [ -f "$OUT/$c.input.json" ] || evaluate "$input" > "$OUT/$c.input.json"
  if [ ! -f "$OUT/$c.json" ]; then
    echo "[$(date +%T)] refining $c" >&2
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e %M" -o "$OUT/$c.time" "$BIN/mesh_refiner" --workspace_path "$ws/dense" \
      --input_path "$input" --output_path "$ws/dense/meshed-refined.ply" ${REFINER_FLAGS:-} > "$OUT/$c.log" 2>&1
    evaluate "$ws/dense/meshed-refined.ply" > "$OUT/$c.json"
  fi
  read -r secs kb < "$OUT/$c.time"
  level=$(grep -m1 -o 'Level 0: [0-9]*x[0-9]* images, [0-9]* faces' "$OUT/$c.log" || true)
  printf '| %s | %s | %s | %.0f | %d | %.4f -> %.4f | %.2f -> %.2f |\n' "$c" "$flags" \
    "${level#Level 0: }" "$secs" "$((kb / 1024))" \
    "$(json_field "$OUT/$c.input.json" accuracy90)" "$(json_field "$OUT/$c.json" accuracy90)" \
    "$(json_field "$OUT/$c.input.json" normal_deg)" "$(json_field "$OUT/$c.json" normal_deg)"
done
} | tee "$OUT/large.md"
