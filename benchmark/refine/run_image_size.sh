#!/usr/bin/env bash
# Choosing --Refine.max_image_size by measurement (issue #10): the cases of
# benchmark/refine/corpus_hd.txt (corpus cases rendered at 1920x1440) refined
# at several working resolutions, through run_corpus.sh (real colmap fusion +
# Poisson, evaluation on the observed surface). Then a table per size: the
# worst case of accuracy90 and normal error relative to the full-resolution
# run, and the time. Results in OUT_DIR are reused.
#
#   bash benchmark/refine/run_image_size.sh OUT_DIR [case ...]
#
# SIZES replaces the sizes (longest side in pixels; -1 = full resolution).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:?usage: $(basename "$0") OUT_DIR [case ...]}
configs=""
for size in ${SIZES:-640 960 1280 1600 -1}; do
  label=$([ "$size" = -1 ] && echo full || echo "$size")
  configs+="$label|--Refine.max_image_size $size"$'\n'
done
CORPUS=benchmark/refine/corpus_hd.txt DEFAULTS=0 BASELINE=0 CONFIGS="$configs" \
  bash benchmark/refine/run_corpus.sh "$@" > /dev/null
python3 benchmark/refine/image_size_table.py "$out/results.tsv" | tee "$out/image_size.md"
