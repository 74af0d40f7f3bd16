#!/usr/bin/env bash
# The demo command: installs what is missing, builds, and runs liftd against its built-in
# simulated lift in the foreground. Ctrl-C stops it.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default --parallel "${LIFTD_JOBS:-$(nproc)}" --target liftd liftctl 2>/dev/null \
  || cmake --build --preset default --parallel "${LIFTD_JOBS:-$(nproc)}"
exec build/bin/liftd --simulate "$@"
