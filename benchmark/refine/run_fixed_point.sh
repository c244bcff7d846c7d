#!/usr/bin/env bash
# Where the refinement's energy settles when it starts from the truth. For
# each corpus case whose workspace run_corpus.sh has made in OUT_DIR,
# mesh_refiner starts from the ground truth itself instead of the Poisson
# mesh: once with no iterations (the truth remeshed to the working edge
# length: what the mesh can hold) and once with the default iterations (or
# the flags in FLAGS). If the second is far worse than the first, the
# energy's fixed point lies away from the truth, and no schedule or start can
# bring a Poisson input closer than it. Prints one row per case with the
# ratios to the Poisson input, next to the defaults' result from the Poisson
# input when run_corpus.sh left it (OUT_DIR/<case>.defaults.json).
#
#   bash benchmark/refine/run_fixed_point.sh OUT_DIR [case ...]
#   FLAGS='--Refine.regularizer none' LABEL=noreg bash benchmark/refine/run_fixed_point.sh OUT_DIR
set -euo pipefail
cd "$(dirname "$0")/../.."
# shellcheck source=benchmark/refine/corpus_lib.sh
source benchmark/refine/corpus_lib.sh
LABEL=${LABEL:-defaults}

cases=$(corpus_cases "$@")

TSV="$OUT/fixed_point.$LABEL.tsv"
: > "$TSV"
for name in $cases; do
  ws="$OUT/$name"
  if [ ! -f "$ws/dense/meshed-poisson.ply" ]; then
    echo "skipping $name: no workspace (run run_corpus.sh $OUT $name first)" >&2
    continue
  fi
  [ -f "$OUT/$name.input.json" ] || evaluate_case "$name" "$ws/dense/meshed-poisson.ply" > "$OUT/$name.input.json"
  for run in gt0 "gt.$LABEL"; do
    out="$OUT/$name.$run.ply"
    if [ ! -f "$OUT/$name.$run.json" ]; then
      echo "[$(date +%T)] $name: $run" >&2
      extra=${FLAGS:-}
      if [ "$run" = gt0 ]; then extra="--Refine.iterations_per_level 0"; fi
      # shellcheck disable=SC2086
      "$BIN/mesh_refiner" --workspace_path "$ws/dense" --input_path "$ws/ground_truth.ply" \
        --output_path "$out" $extra > "$OUT/$name.$run.log" 2>&1
      evaluate_case "$name" "$out" > "$OUT/$name.$run.json"
    fi
  done
  printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$(cat "$OUT/$name.input.json")" \
    "$(cat "$OUT/$name.gt0.json")" "$(cat "$OUT/$name.gt.$LABEL.json")" \
    "$(cat "$OUT/$name.defaults.json" 2>/dev/null || echo '{}')" >> "$TSV"
done

python3 - "$TSV" "$LABEL" <<'EOF'
import json, sys
rows = [l.rstrip('\n').split('\t') for l in open(sys.argv[1]) if l.strip()]
label = sys.argv[2]
print(f"| case | Poisson input acc90 / normal | truth remeshed, x input | truth after {label}, x input | Poisson after defaults, x input |")
print("|---|---|---|---|---|")
for name, *js in rows:
    inp, gt0, gt, poisson = (json.loads(j) for j in js)
    def r(m):
        if not m: return "-"
        return f"{m['accuracy90'] / inp['accuracy90']:.3f} / {m['normal_deg'] / inp['normal_deg']:.3f}"
    print(f"| {name} | {inp['accuracy90']:.4f} / {inp['normal_deg']:.2f} | {r(gt0)} | {r(gt)} | {r(poisson)} |")
EOF
