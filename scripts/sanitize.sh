#!/usr/bin/env bash
# Builds with AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer)
# into build-asan/ and runs tests under them. See docs/fuzzing.md.
#
#   bash scripts/sanitize.sh          # subset: the reader tests (colmap_io_*, util_test) and
#                                     # the command-line tests (mesh_refiner_cli_test,
#                                     # mesh_programs_cli_test, bad_input_table_test if present)
#   bash scripts/sanitize.sh --full   # the whole suite through ctest
#
# Any sanitizer report fails the run (exit 1), also one from a program a test
# started and whose failure the test expected: reports go to
# build-asan/sanitizer-logs/ as well and are checked after the tests.
# Leaks inside the EGL/Mesa stack at exit are suppressed (scripts/lsan.supp).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build-asan}
JOBS=${JOBS:-$(nproc)}
mode=subset
case "${1:-}" in
  "") ;;
  --full) mode=full ;;
  -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
  *) echo "sanitize.sh: unknown argument $1 (expected --full or nothing)" >&2; exit 2 ;;
esac

start=$(date +%s)
# -O1 -g1: line tables for the reports; -O1 halves the build (remesh.cc: 184 s at -O1, 386 s at
# -O2, with both sanitizers), the tests run about as fast.
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DMR_SANITIZE=ON -DMR_TEST_TIMEOUT=2400 \
  >/dev/null

READER_TESTS=(colmap_io_camera_models_test colmap_io_sparse_model_test colmap_io_dense_array_test
              colmap_io_undistortion_test colmap_io_workspace_test colmap_io_ply_test
              colmap_io_mesh_io_test colmap_io_image_file_test util_test)
CLI_TESTS=(mesh_refiner_cli_test mesh_programs_cli_test)
if grep -q "bad_input_table_test" tests/CMakeLists.txt 2>/dev/null; then
  CLI_TESTS+=(bad_input_table_test)
fi
if [ "$mode" = full ]; then
  cmake --build "$BUILD" -j "$JOBS"
else
  targets=()
  for t in "${READER_TESTS[@]}" "${CLI_TESTS[@]}"; do targets+=(--target "$t"); done
  cmake --build "$BUILD" -j "$JOBS" "${targets[@]}"
fi
built=$(date +%s)
echo "sanitize.sh: built ($mode) in $(( built - start )) s"

logs=$PWD/$BUILD/sanitizer-logs
rm -rf "$logs"
mkdir -p "$logs"
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:log_path=$logs/asan"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:log_path=$logs/ubsan"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0"
export QT_QPA_PLATFORM=offscreen

failed=0
if [ "$mode" = full ]; then
  (cd "$BUILD" && ctest --output-on-failure -j "$JOBS") || failed=1
else
  for t in "${READER_TESTS[@]}" "${CLI_TESTS[@]}"; do
    t0=$(date +%s)
    if "$BUILD/tests/$t" --gtest_brief=1 >"$logs/$t.out" 2>&1; then
      echo "sanitize.sh: $t passed ($(( $(date +%s) - t0 )) s)"
    else
      failed=1
      echo "sanitize.sh: $t FAILED ($(( $(date +%s) - t0 )) s):"
      tail -40 "$logs/$t.out"
    fi
  done
fi

reports=$(find "$logs" -name 'asan.*' -o -name 'ubsan.*' | sort)
if [ -n "$reports" ]; then
  failed=1
  echo "sanitize.sh: sanitizer reports:"
  for r in $reports; do echo "== $r"; head -60 "$r"; done
fi
echo "sanitize.sh: $mode: build $(( built - start )) s, tests $(( $(date +%s) - built )) s"
[ "$failed" -eq 0 ] || { echo "sanitize.sh: FAILED"; exit 1; }
echo "sanitize.sh: passed"
