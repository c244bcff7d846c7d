# Sourced by run_corpus.sh, run_fixed_point.sh and run_cameras.sh, from the
# checkout's root with their arguments (OUT_DIR [case ...]): sets OUT (made
# absolute and created), BIN, MODELS, CORPUS (benchmark/refine/corpus.txt
# unless set), shifts OUT_DIR off the arguments, and defines case_flags NAME
# (the case's workspace_synthesizer flags from corpus.txt, with the model
# path made absolute), case_eval_flags, corpus_cases and evaluate_case.
OUT=${1:?usage: $(basename "$0") OUT_DIR [case ...]}
shift
OUT=$(realpath -m "$OUT")
BIN=${BIN:-$PWD/build/bin}
MODELS=$(realpath ../shared/data/models)
CORPUS=${CORPUS:-benchmark/refine/corpus.txt}
export QT_QPA_PLATFORM=offscreen
mkdir -p "$OUT"

case_flags() {
  local line
  line=$(grep -E "^$1\s*\|" "$CORPUS") || { echo "unknown case: $1" >&2; exit 2; }
  line=${line#*|}
  echo "${line%%|*}" | sed "s#--model_path #--model_path $MODELS/#"
}

# case_eval_flags NAME: the case's mesh_evaluator flags (corpus.txt's optional
# third field), e.g. a --region_box.
case_eval_flags() {
  local line
  line=$(grep -E "^$1\s*\|" "$CORPUS") || { echo "unknown case: $1" >&2; exit 2; }
  line=${line#*|}
  case "$line" in *"|"*) echo "${line#*|}" ;; esac
}

# corpus_cases [case ...]: the cases given, or every case of $CORPUS.
corpus_cases() {
  if [ $# -gt 0 ]; then echo "$*"; return; fi
  grep -v '^#' "$CORPUS" | grep -v '^\s*$' | cut -d'|' -f1 | tr -d ' '
}

# evaluate_case NAME MESH: mesh_evaluator's JSON for MESH against the case's
# ground truth in OUT, on the surface its cameras observe.
evaluate_case() {
  # shellcheck disable=SC2046
  "$BIN/mesh_evaluator" --input_path "$2" --gt_path "$OUT/$1/ground_truth.ply" \
    --workspace_path "$OUT/$1/dense" $(case_eval_flags "$1")
}
