#!/usr/bin/env bash
# The test command: installs what is missing, builds the default and the sanitizer preset,
# runs every test in both (tests labelled "slow" in the default preset only: real-time
# end-to-end runs the sanitizers add nothing to), then runs each fuzz target briefly, and
# prints how long each part took. Exits non-zero on any failure.
#   tools/test.sh            everything
#   LIFTD_SKIP_ASAN=1 ...    skip the sanitizer build (quicker local runs)
#   LIFTD_SKIP_FUZZ=1 ...    skip the fuzz targets
#   LIFTD_SOAK_SECONDS=N     fault soak length after the default tests (default 60; 0 skips)
#   LIFTD_SKIP_SYSTEMD=1 ... skip the systemd stage (tests/systemd/stage.sh: the package on
#                            Debian 12 with systemd as PID 1 under user-mode Linux)
#   LIFTD_JOBS=N, LIFTD_TEST_JOBS=M   build with N jobs (default: cores), run M tests at once
#                            (default: N + 1)
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install-deps.sh
jobs=${LIFTD_JOBS:-$(nproc)}
# One test more than cores: the process tests spend nearly all their time waiting on a simulated
# car in real time (a whole run uses about 3 minutes of CPU in its 12 minutes of tests), so a third
# test on two cores costs them nothing. Never a build beside them: a compiler's load delays even
# SCHED_FIFO cycle threads by several ms on these machines (measured: 12 ms), which a real-time
# test rightly fails on. The RUN_SERIAL tests always run alone.
test_jobs=${LIFTD_TEST_JOBS:-$((jobs + 1))}

timings=()
timed() {  # timed LABEL COMMAND...: runs it and notes how long it took
  local label=$1 start=$SECONDS
  shift
  "$@"
  timings+=("$(printf '%-22s %5d s' "$label" $((SECONDS - start)))")
}

run_preset() {
  local preset=$1
  shift
  echo "=== preset: $preset ==="
  cmake --preset "$preset" >/dev/null
  timed "$preset build" cmake --build --preset "$preset" --parallel "$jobs"
  timed "$preset tests" ctest --preset "$preset" --parallel "$test_jobs" "$@"
}

run_preset default
soak_seconds=${LIFTD_SOAK_SECONDS:-60}
if [ "$soak_seconds" != 0 ]; then
  echo "=== fault soak: $soak_seconds s ==="
  timed "soak" tools/soak --seconds "$soak_seconds" --seed 1
fi
# The installed service as an operator meets it: Debian 12 booted with systemd as PID 1 under
# user-mode Linux (its root file system cached in /var/cache/liftd-uml; first run: + 3-4 min).
if [ "${LIFTD_SKIP_SYSTEMD:-0}" != 1 ]; then
  echo "=== systemd stage ==="
  timed "systemd stage" tests/systemd/stage.sh build
fi
[ "${LIFTD_SKIP_ASAN:-0}" = 1 ] || run_preset asan -LE slow
if [ "${LIFTD_SKIP_FUZZ:-0}" != 1 ]; then
  echo "=== preset: fuzz ==="
  cmake --preset fuzz >/dev/null
  timed "fuzz build" cmake --build --preset fuzz --parallel "$jobs"
  timed "fuzz runs" ctest --preset fuzz --parallel "$jobs"  # one core per fuzz target
fi
echo "tools/test.sh: all presets passed"
printf '  %s\n' "${timings[@]}"
