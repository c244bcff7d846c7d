#!/usr/bin/env bash
# Installs missing packages, builds, and runs the whole test suite; then the
# hardening stages (docs/fuzzing.md): the reader and command-line tests under
# ASan+UBSan (scripts/sanitize.sh, build-asan/) and a fuzz smoke run of every
# harness (scripts/fuzz.sh, build-fuzz/, FUZZ_SECONDS per harness). A finding
# in either fails the run. MR_SANITIZE_STAGE=0 / MR_FUZZ_STAGE=0 skip them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
(
  cd build
  export QT_QPA_PLATFORM=offscreen
  ctest --output-on-failure -j "${JOBS:-$(nproc)}" --timeout 900
)
if [ "${MR_SANITIZE_STAGE:-1}" != 0 ]; then
  t0=$SECONDS
  bash scripts/sanitize.sh
  echo "run_tests.sh: sanitizer stage took $(( SECONDS - t0 )) s"
fi
if [ "${MR_FUZZ_STAGE:-1}" != 0 ]; then
  t0=$SECONDS
  bash scripts/fuzz.sh --time "${FUZZ_SECONDS:-30}"
  echo "run_tests.sh: fuzz smoke stage took $(( SECONDS - t0 )) s"
fi
