#!/usr/bin/env bash
# How mesh_refiner's time per iteration grows (issue #10): on one workspace
# (run_large.sh's case a: 40 views of 1920x1440), 3 iterations at one level
#   - against pixels x views: --Refine.max_image_size 320 .. 1920 with the
#     face count held by --Refine.max_faces (target_edge_px small enough that
#     the budget binds at every size);
#   - against faces: --Refine.max_faces 50k .. 800k at max_image_size 640.
# Each run's time per iteration is the median of its iterations (the log's
# table); the split (data, silhouette, denoise, clean-up) is kept too.
# Writes OUT_DIR/scaling.tsv, then plot_scaling.py draws the log-log plot
# with its fitted slopes (docs/images/scaling.svg).
#
#   bash benchmark/refine/run_scaling.sh WORKSPACE OUT_DIR
#
# WORKSPACE is a folder with dense/ and ground_truth.ply, e.g. /tmp/large/a
# after `bash benchmark/refine/run_large.sh /tmp/large a`.
set -euo pipefail
cd "$(dirname "$0")/../.."
WS=$(realpath "${1:?usage: $(basename "$0") WORKSPACE OUT_DIR}")
OUT=$(realpath -m "${2:?usage: $(basename "$0") WORKSPACE OUT_DIR}")
BIN=${BIN:-$PWD/build/bin}
export QT_QPA_PLATFORM=offscreen
mkdir -p "$OUT"
[ -f "$WS/dense/meshed-poisson.ply" ] || { echo "no $WS/dense/meshed-poisson.ply" >&2; exit 2; }

# sweep size faces: one run (reused when its log exists); prints its TSV row.
run() {
  local size=$1 faces=$2 stem="$OUT/s$1_f$2"
  if [ ! -f "$stem.done" ]; then
    echo "[$(date +%T)] max_image_size $size, max_faces $faces" >&2
    "$BIN/mesh_refiner" --workspace_path "$WS/dense" --output_path "$stem.ply" \
      --Refine.num_levels 1 --Refine.iterations_per_level 3 --Refine.pair_halves_min_views 0 \
      --Refine.max_image_size "$size" --Refine.max_faces "$faces" \
      --Refine.target_edge_px 0.25 > "$stem.log" 2>&1
    rm -f "$stem.ply"
    touch "$stem.done"
  fi
  python3 - "$stem.log" <<'EOF'
import re, statistics, sys
log = open(sys.argv[1]).read()
w, h, faces = map(int, re.search(r"Level 0: (\d+)x(\d+) images, (\d+) faces", log).groups())
views = int(re.search(r"views (\d+), pairs", log).group(1))
rows = re.findall(r"; ([\d.]+) s \(data ([\d.]+), silhouette ([\d.]+), denoise ([\d.]+), "
                  r"clean-up ([\d.]+); (\d+) renders\)", log)
cols = list(zip(*[[float(x) for x in r] for r in rows]))
med = [statistics.median(c) for c in cols]
print("\t".join(str(x) for x in [w, h, views, w * h * views, faces] +
                ["%.3f" % m for m in med[:5]] + ["%d" % med[5]]))
EOF
}

{
  printf 'width\theight\tviews\tpixels_x_views\tfaces\tseconds\tdata\tsilhouette\tdenoise\tcleanup\trenders\tsweep\n'
  for size in 320 640 1280 1920; do printf '%s\tpixels\n' "$(run "$size" 100000)"; done
  for faces in 50000 100000 200000 400000 800000; do printf '%s\tfaces\n' "$(run 640 "$faces")"; done
} > "$OUT/scaling.tsv"
cat "$OUT/scaling.tsv"
python3 benchmark/refine/plot_scaling.py "$OUT/scaling.tsv" "$OUT/scaling.svg"
