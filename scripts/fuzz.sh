#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, clang, ASan+UBSan) into build-fuzz/
# and runs each on its seed corpus, one after the other. See docs/fuzzing.md.
#
#   bash scripts/fuzz.sh                      # every harness for 30 s
#   bash scripts/fuzz.sh --time 600 ply obj   # these two for 10 minutes each
#   bash scripts/fuzz.sh --runs 10000000      # every harness for 10M executions
#   bash scripts/fuzz.sh --runs 10000000 --time 900   # whichever comes first
#   bash scripts/fuzz.sh --strict ...         # exceptions other than mr::InputError are findings
#   bash scripts/fuzz.sh --build-only
#
# Prints per harness: executions, exec/s, libFuzzer's cov: (edges) and ft:
# (features), the corpus size, findings and seconds. Exits 1 if any harness
# found a crash, a sanitizer report, a leak, a timeout (-timeout, default
# 10 s per input, TIMEOUT=60 to change; also the slow-unit report's bound) or
# an out-of-memory (-rss_limit_mb 2048); the input is
# saved under build-fuzz/artifacts/<harness>/ and the log beside it.
# New inputs the fuzzer finds go to build-fuzz/corpus/<harness>/ (kept
# between runs; fuzz/corpus/ holds only the seeds).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build-fuzz}
JOBS=${JOBS:-$(nproc)}
TIMEOUT=${TIMEOUT:-10}

# -max_len per harness: a little above the largest seed (bytes).
declare -A MAX_LEN=(
  [ply]=16384 [obj]=32768 [dense_array]=16384 [fused_vis]=4096 [ini]=8192 [image]=8192
  [cameras_bin]=4096 [images_bin]=4096 [points3D_bin]=4096
  [cameras_txt]=4096 [images_txt]=4096 [points3D_txt]=4096
)
ALL=(ply obj dense_array fused_vis ini image cameras_bin images_bin points3D_bin
     cameras_txt images_txt points3D_txt)

limit=()
build_only=0
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --time) limit+=(-max_total_time="$2"); shift 2 ;;
    --runs) limit+=(-runs="$2"); shift 2 ;;
    --strict) export MR_FUZZ_STRICT=1; shift ;;
    --build-only) build_only=1; shift ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) [ -n "${MAX_LEN[$1]:-}" ] || { echo "fuzz.sh: unknown harness $1 (${ALL[*]})" >&2; exit 2; }
       harnesses+=("$1"); shift ;;
  esac
done
[ ${#harnesses[@]} -gt 0 ] || harnesses=("${ALL[@]}")
[ ${#limit[@]} -gt 0 ] || limit=(-max_total_time=30)

CXX_CLANG=${CXX_CLANG:-clang++}
command -v "$CXX_CLANG" >/dev/null || { echo "fuzz.sh: $CXX_CLANG not found (scripts/install_deps.sh)" >&2; exit 2; }
start=$(date +%s)
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$CXX_CLANG" \
  -DMR_FUZZ=ON >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=(--target "fuzz_$h"); done
cmake --build "$BUILD" -j "$JOBS" "${targets[@]}"
echo "fuzz.sh: built ${#harnesses[@]} harnesses in $(( $(date +%s) - start )) s"
[ "$build_only" -eq 0 ] || exit 0

export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
findings=0
rows=()
for h in "${harnesses[@]}"; do
  corpus=$BUILD/corpus/$h
  artifacts=$BUILD/artifacts/$h
  mkdir -p "$corpus" "$artifacts"
  log=$artifacts/last.log
  before=$(ls "$artifacts" | grep -cE '^(crash|leak|timeout|oom|slow-unit)-' || true)
  t0=$(date +%s)
  echo "fuzz.sh: $h ${limit[*]} -max_len=${MAX_LEN[$h]} (log: $log)"
  set +e
  "$BUILD/fuzz/fuzz_$h" "${limit[@]}" -max_len="${MAX_LEN[$h]}" -timeout="$TIMEOUT" \
    -report_slow_units="$TIMEOUT" \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts/" \
    "$corpus" "fuzz/corpus/$h" >"$log" 2>&1
  rc=$?
  set -e
  seconds=$(( $(date +%s) - t0 ))
  after=$(ls "$artifacts" | grep -cE '^(crash|leak|timeout|oom|slow-unit)-' || true)
  stat() { { grep -oE "stat::$1: *[0-9]+" "$log" || true; } | awk '{print $2}' | tail -1; }
  execs=$(stat number_of_executed_units)
  rate=$(stat average_exec_per_sec)
  status=$({ grep -E '^#[0-9]+.*cov: ' "$log" || true; } | tail -1)
  cov=$(sed -nE 's/.* cov: ([0-9]+).*/\1/p' <<<"$status")
  ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$status")
  corp=$(sed -nE 's/.* corp: ([0-9]+\/[0-9]+[a-zA-Z]*).*/\1/p' <<<"$status")
  found=$(( after - before ))
  if [ "$rc" -ne 0 ] && [ "$found" -eq 0 ]; then found=1; fi  # e.g. a non-std exception
  if [ "$found" -ne 0 ]; then
    findings=$(( findings + found ))
    echo "fuzz.sh: $h FOUND a problem (exit $rc):"
    grep -E 'ERROR|SUMMARY|MR_FUZZ_STRICT|Test unit written|terminate' "$log" | head -20 || true
  fi
  rows+=("$(printf '%-13s %11s %7s %6s %7s %13s %8s %7s' "$h" "${execs:-?}" "${rate:-?}" \
    "${cov:-?}" "${ft:-?}" "${corp:-?}" "$found" "$seconds")")
done

printf '\n%-13s %11s %7s %6s %7s %13s %8s %7s\n' harness execs exec/s cov ft corpus findings seconds
printf '%s\n' "${rows[@]}"
echo "fuzz.sh: $(( $(date +%s) - start )) s in all, $findings finding(s)"
[ "$findings" -eq 0 ]
