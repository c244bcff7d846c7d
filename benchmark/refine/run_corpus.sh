#!/usr/bin/env bash
# mesh_refiner on the development corpus (benchmark/refine/corpus.txt): for
# each case, workspace_synthesizer (real colmap stereo_fusion +
# poisson_mesher), then mesh_refiner in each configuration, then
# mesh_evaluator on the observed surface (ground-truth faces seen by >= 2
# cameras). Prints one row per case and configuration, with the ratios to the
# Poisson input and the issue's floors (accuracy90 <= 0.6x, normal error <=
# 0.7x, completeness no more than 1 point lower), then the worst case of each
# column per configuration. Workspaces and results in OUT_DIR are reused
# (delete a case's folder, or its OUT_DIR/<case>.<config>.* files, to redo).
#
#   bash benchmark/refine/run_corpus.sh OUT_DIR [case ...]
#
# Configurations: "defaults" (no flag) and the isotropic baseline
# "zncc+laplacian"; CONFIGS adds more, one "label|flags" per line, e.g.
#   CONFIGS='lp|--Refine.regularizer lp' bash benchmark/refine/run_corpus.sh /tmp/corpus
# BASELINE=0 leaves the baseline out, DEFAULTS=0 the defaults; BIN points
# at another build's bin/. NOMASK=1 refines every case without its masks (a
# workspace of links, OUT_DIR/<case>.nomask/dense, beside the original; the
# results get ".nomask" in their names; the evaluation is the same).
set -euo pipefail
cd "$(dirname "$0")/../.."
# shellcheck source=benchmark/refine/corpus_lib.sh
source benchmark/refine/corpus_lib.sh

configs=""
if [ "${DEFAULTS:-1}" != 0 ]; then configs+="defaults|"$'\n'; fi
if [ "${BASELINE:-1}" != 0 ]; then
  configs+="zncc+laplacian|--Refine.similarity zncc --Refine.regularizer laplacian --Refine.open_border_rings 0"$'\n'
fi
if [ -n "${CONFIGS:-}" ]; then configs+=$'\n'"$CONFIGS"; fi

cases=$(corpus_cases "$@")

TSV="$OUT/results.tsv"
: > "$TSV"
for name in $cases; do
  flags=$(case_flags "$name")
  ws="$OUT/$name"
  if [ ! -f "$ws/dense/meshed-poisson.ply" ]; then
    rm -rf "$ws"
    echo "[$(date +%T)] synthesising $name" >&2
    # shellcheck disable=SC2086
    "$BIN/workspace_synthesizer" --output_path "$ws" $flags > "$OUT/$name.synth.log" 2>&1
  fi
  if [ ! -f "$OUT/$name.input.json" ]; then
    evaluate_case "$name" "$ws/dense/meshed-poisson.ply" > "$OUT/$name.input.json"
  fi
  printf '%s\tinput\t%s\t0\t0\n' "$name" "$(cat "$OUT/$name.input.json")" >> "$TSV"
  while IFS= read -r config; do
    [ -z "$config" ] && continue
    label=${config%%|*}
    rflags=${config#*|}
    suffix=""
    refine_ws="$ws/dense"
    if [ "${NOMASK:-0}" = 1 ]; then
      suffix=".nomask"
      refine_ws="$OUT/$name.nomask/dense"
      if [ ! -d "$refine_ws" ]; then
        mkdir -p "$refine_ws"
        for f in images sparse meshed-poisson.ply; do ln -s "$ws/dense/$f" "$refine_ws/$f"; done
      fi
    fi
    out="$ws/dense/meshed-refined-${label//[^A-Za-z0-9_.-]/_}$suffix.ply"
    stem="$OUT/$name.${label//[^A-Za-z0-9_.-]/_}$suffix"
    if [ ! -f "$stem.json" ]; then
      echo "[$(date +%T)] $name: $label" >&2
      # shellcheck disable=SC2086
      /usr/bin/time -f "%e %M" -o "$stem.time" "$BIN/mesh_refiner" --workspace_path "$refine_ws" \
        --output_path "$out" $rflags > "$stem.log" 2>&1 || {
          echo "mesh_refiner failed on $name ($label): see $stem.log" >&2; continue; }
      evaluate_case "$name" "$out" > "$stem.json"
    fi
    read -r secs kb < "$stem.time"
    printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$label$suffix" "$(cat "$stem.json")" "$secs" "$((kb / 1024))" >> "$TSV"
  done <<< "$configs"
done
python3 benchmark/refine/corpus_table.py "$TSV" | tee "$OUT/results.md"
