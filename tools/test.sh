#!/usr/bin/env bash
# The test command: installs what is missing, builds the default and the sanitizer preset,
# runs every test in both, then runs each fuzz target briefly. Exits non-zero on any failure.
#   tools/test.sh            everything
#   LIFTD_SKIP_ASAN=1 ...    skip the sanitizer build (quicker local runs)
#   LIFTD_SKIP_FUZZ=1 ...    skip the fuzz targets
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install-deps.sh
jobs=${LIFTD_JOBS:-$(nproc)}

run_preset() {
  local preset=$1
  echo "=== preset: $preset ==="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" --parallel "$jobs"
  ctest --preset "$preset" --parallel "$jobs"
}

run_preset default
[ "${LIFTD_SKIP_ASAN:-0}" = 1 ] || run_preset asan
if [ "${LIFTD_SKIP_FUZZ:-0}" != 1 ]; then
  echo "=== preset: fuzz ==="
  cmake --preset fuzz >/dev/null
  cmake --build --preset fuzz --parallel "$jobs"
  ctest --preset fuzz
fi
echo "tools/test.sh: all presets passed"
