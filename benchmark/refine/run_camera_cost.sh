#!/usr/bin/env bash
# What camera refinement costs (issue #11: at most +25 % of a run's wall time
# on the example). Makes the README's example workspace in OUT_DIR (as
# scripts/run_example.sh does, with this build's workspace_synthesizer), then
# refines a fresh copy of it without camera refinement and with it, REPS
# times each, the configurations alternating so that a drift of the machine
# falls on all of them. Prints each run's wall time and peak memory, each
# camera round's seconds (of which picking the samples) and Ceres
# iterations, and then per configuration the median wall time and its excess
# over the median without camera refinement. Run it on an otherwise idle
# machine.
#
#   bash benchmark/refine/run_camera_cost.sh OUT_DIR
#
# REPS (default 3) sets the runs per configuration; CONFIGS replaces the
# configurations ("label|flags" per line; the first is the reference); BIN
# points at another build's bin/.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(realpath -m "${1:?usage: $(basename "$0") OUT_DIR}")
BIN=${BIN:-$PWD/build/bin}
reps=${REPS:-3}
configs=${CONFIGS:-$'none|\ntwo rounds (default)|--Refine.refine_cameras poses\nthree rounds|--Refine.refine_cameras poses --Refine.camera_rounds 3'}
mkdir -p "$out"
if [ ! -f "$out/example/dense/meshed-poisson.ply" ]; then
  rm -rf "$out/example"
  echo "[$(date +%T)] synthesising the example workspace" >&2
  "$BIN/workspace_synthesizer" --output_path "$out/example" > "$out/synth.log" 2>&1
fi

times="$out/times.tsv"
: > "$times"
for rep in $(seq 1 "$reps"); do
  k=0
  while IFS= read -r config; do
    [ -z "$config" ] && continue
    k=$((k + 1))
    label=${config%%|*}
    flags=${config#*|}
    run="$out/run"
    rm -rf "$run"
    cp -r "$out/example" "$run"
    log="$out/config$k.rep$rep.log"
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e %M" -o "$out/time" "$BIN/mesh_refiner" --workspace_path "$run/dense" \
      $flags > "$log" 2>&1 || { echo "mesh_refiner failed ($label): see $log" >&2; exit 1; }
    read -r seconds kb < "$out/time"
    rounds=$(grep -E '^I .*\] Camera refinement \(' "$log" |
      sed -nE 's/.* in ([0-9]+) iterations.*; ([0-9.]+) s \(samples ([0-9.]+) s\).*/\2 s (samples \3 s, \1 iterations)/p' |
      paste -sd ';' - || true)
    printf '%s\t%s\t%s\n' "$k" "$label" "$seconds" >> "$times"
    echo "$label, run $rep: $seconds s, $((kb / 1024)) MB${rounds:+; rounds: $rounds}"
  done <<< "$configs"
done
rm -rf "$out/run" "$out/time"

echo
echo "| configuration | wall s (runs) | median s | over the first |"
echo "|---|---|---|---|"
python3 - "$times" <<'EOF'
import statistics
import sys
runs = {}
for line in open(sys.argv[1]):
    k, label, seconds = line.rstrip("\n").split("\t")
    runs.setdefault((int(k), label), []).append(float(seconds))
configs = sorted(runs.items())
reference = statistics.median(configs[0][1])
for (k, label), seconds in configs:
    median = statistics.median(seconds)
    over = "" if k == 1 else f"{100 * (median / reference - 1):+.1f} %"
    listed = ", ".join(f"{s:.2f}" for s in seconds)
    print(f"| {label} | {listed} | {median:.2f} | {over} |")
EOF
