#!/usr/bin/env bash
# The test command: installs what is missing, builds the default and the sanitizer preset,
# runs every test in both (tests labelled "slow" in the default preset only: real-time
# end-to-end runs the sanitizers add nothing to), then runs each fuzz target briefly, and
# prints how long each part took. Exits non-zero on any failure.
#   tools/test.sh            everything
#   tools/test.sh --under-load   only the default build's tests, while two CPU hogs and a disk
#                            writer run beside them at normal priority (the suite must not
#                            flake on a busy machine)
#   LIFTD_SKIP_ASAN=1 ...    skip the sanitizer build (quicker local runs)
#   LIFTD_SKIP_UML=1 ...     skip both user-mode Linux stages (real SocketCAN, systemd)
#   LIFTD_SKIP_VM=1 ...      skip the real-UART stage (tools/vm/serial-stage.sh: liftd in a QEMU
#                            guest on the 16550A and an FTDI USB adapter, 3 to 5 minutes)
#   LIFTD_SKIP_SYSTEMD=1 ... skip the systemd stage (tests/systemd/stage.sh: the package on Debian
#                            12 with systemd as PID 1 under user-mode Linux, 3 to 5 minutes)
#   LIFTD_SKIP_FUZZ=1 ...    skip the fuzz targets
#   LIFTD_SOAK_SECONDS=N     each drive kind's soak after the default tests (default 45; 0 skips)
#   LIFTD_JOBS=N, LIFTD_TEST_JOBS=M   build with N jobs (default: cores), run M tests at once
#                            (default: 3 N; N + 1 under load)
set -euo pipefail
cd "$(dirname "$0")/.."
under_load=0
[ "${1:-}" = --under-load ] && under_load=1

jobs=${LIFTD_JOBS:-$(nproc)}
systemd_stage=0
[ $under_load = 0 ] && [ "${LIFTD_SKIP_UML:-0}" != 1 ] && [ "${LIFTD_SKIP_SYSTEMD:-0}" != 1 ] &&
  systemd_stage=1
if [ $under_load = 0 ] && [ "${LIFTD_SKIP_UML:-0}" != 1 ]; then
  tools/install-deps.sh --with-uml  # one apt-get run for the build and both user-mode Linux stages
else
  tools/install-deps.sh
fi
if [ $systemd_stage = 1 ] && [ "$(id -u)" = 0 ]; then
  # The systemd stage's Debian 12 root file system (cached; on a fresh machine 3-4 minutes of
  # downloads and unpacking) is built beside the compilers; the stage waits for it. Nothing that
  # runs meanwhile keeps time, so it delays nothing but the builds a little.
  mkdir -p build
  tests/systemd/build-rootfs.sh >build/rootfs.log 2>&1 &
  rootfs_pid=$!
fi
background=()  # what runs beside the foreground; a failure ends it too
trap 'kill "${background[@]}" 2>/dev/null || true' EXIT
[ -n "${rootfs_pid:-}" ] && background+=("$rootfs_pid")
# Three tests per core: the process tests spend nearly all their time waiting on a simulated car
# in real time (measured on 2 cores: the whole default suite used 75 s of CPU in 364 s at 3 tests
# at once, and passed in 221 s at 6), so more of them side by side cost each other nothing. Never
# a build beside them: a compiler's load delays even SCHED_FIFO cycle threads by several ms on
# these machines (measured: 12 ms), which a real-time test rightly fails on. The RUN_SERIAL tests
# always run alone. Under --under-load one test more than cores: the hogs take the CPUs.
# The sanitizer build's tests, one more than cores: its code runs several times slower, so its
# tests keep the CPUs busy.
test_jobs=${LIFTD_TEST_JOBS:-$((under_load == 1 ? jobs + 1 : jobs * 3))}
asan_test_jobs=${LIFTD_TEST_JOBS:-$((jobs + 1))}

timings=()
timed() {  # timed LABEL COMMAND...: runs it and notes how long it took
  local label=$1 start=$SECONDS
  shift
  "$@"
  timings+=("$(printf '%-22s %5d s' "$label" $((SECONDS - start)))")
}

# seed_test_costs PRESET BINARY_DIR: ctest starts the tests it knows to be long first, from the
# costs it wrote in its last run; a fresh checkout has none and would start them in declaration
# order. Seeded, CI runs the same mix of tests side by side as every run on a developer's machine
# after the first (what passes there under load is what CI runs). tests/ctest-costs/PRESET.txt
# holds what a full run measured for the tests of a second or more (ctest's own file format:
# name, runs, seconds); only the order depends on it. Measured: the default tests take about as
# long either way (225 s seeded, 227 s not).
preset_binary_dir() {  # the binaryDir of CMakePresets.json
  if [ "$1" = default ]; then echo build; else echo "build-$1"; fi
}
seed_test_costs() {
  local costs=$2/Testing/Temporary/CTestCostData.txt
  [ -e "$costs" ] && return 0
  mkdir -p "$(dirname "$costs")"
  cp "tests/ctest-costs/$1.txt" "$costs"
}

run_preset() {  # run_preset PRESET TEST_JOBS [CTEST ARGS...]
  local preset=$1 parallel=$2
  shift 2
  echo "=== preset: $preset ==="
  cmake --preset "$preset" >/dev/null
  timed "$preset build" cmake --build --preset "$preset" --parallel "$jobs"
  seed_test_costs "$preset" "$(preset_binary_dir "$preset")"
  timed "$preset tests" ctest --preset "$preset" --parallel "$parallel" "$@"
}

# start_session SCRIPT: runs it in a session of its own (setsid) and prints the session's process
# group, so that `kill -- -GROUP` ends all of it (a loop and the command it is waiting for). The
# session gets none of this shell's descriptors: called as $(start_session ...), a session that
# kept the substitution's pipe as its output would keep the caller waiting for as long as it
# runs (a CPU hog: for ever). SCRIPT redirects its own output where it wants it kept.
start_session() {
  local pid_file
  pid_file=$(mktemp)
  setsid -f bash -c 'echo $$ >"$1"; eval "$2"' session "$pid_file" "$1" </dev/null >/dev/null 2>&1
  for _ in $(seq 100); do [ -s "$pid_file" ] && break; sleep 0.05; done
  cat "$pid_file"
  rm -f "$pid_file"
}

# A user-mode Linux guest uses one CPU at most (its kernel is uniprocessor). Beside it the other
# CPU compiles the fuzz and sanitizer presets with ONE job at nice 19, so the guest keeps a CPU
# of its own (measured: with a compiler on both CPUs, even at nice 19 and with the guest at
# SCHED_FIFO, the guest's cycle woke up to 7.5 ms late and its encoder went stale mid-travel).
# The builder runs in its own session, so that one kill ends ninja and its compiler when the
# stage is done; what it finished stays built (ninja logs each output as it completes) and the
# presets below build the rest with every CPU.
builder=
start_early_builds() {
  local builds=() script
  [ "${LIFTD_SKIP_FUZZ:-0}" = 1 ] || builds+=("cmake --preset fuzz >/dev/null && cmake --build --preset fuzz --parallel 1")
  [ "${LIFTD_SKIP_ASAN:-0}" = 1 ] || builds+=("cmake --preset asan >/dev/null && cmake --build --preset asan --parallel 1")
  [ ${#builds[@]} -gt 0 ] || return 0
  script=$(printf '%s && ' "${builds[@]}")
  builder=$(start_session "exec >>build/early-builds.log 2>&1; nice -n 19 bash -c '${script% && }'")
  trap 'kill "${background[@]}" 2>/dev/null || true; stop_early_builds' EXIT
}
stop_early_builds() {
  [ -z "$builder" ] || kill -- "-$builder" 2>/dev/null || true
  builder=
}

if [ $under_load = 1 ]; then
  echo "=== preset: default (built before the load starts) ==="
  cmake --preset default >/dev/null
  timed "default build" cmake --build --preset default --parallel "$jobs"
  seed_test_costs default build
  # Two CPU hogs and a disk writer at normal priority (nice 0) for as long as the tests run,
  # each in a session of its own (setsid), as any other program on a machine runs: with the
  # kernel's autogroups a session is one scheduling group. Started inside this script's
  # session, a hog made the tests' group always runnable, and the tty's flip-buffer worker (a
  # normal-priority kernel thread that carries every byte of a pseudo-terminal, see
  # docs/architecture.md) then waited up to 2.5 s for a CPU (tools/bench/trace_tty_worker.sh),
  # so replies reached no master in time. The load is the same either way: two CPUs' worth of
  # spinning and a writer that syncs 256 MB again and again.
  load_pids=()
  start_load() { load_pids+=("$(start_session "$1")"); }
  # The whole group: the writer's loop and the dd it is waiting for.
  stop_load() { for p in "${load_pids[@]}"; do kill -- "-$p" 2>/dev/null || true; done; rm -f build/under-load.tmp; }
  trap stop_load EXIT
  mkdir -p build
  for _ in 1 2; do start_load 'while :; do :; done'; done
  start_load 'while :; do dd if=/dev/zero of=build/under-load.tmp bs=1M count=256 conv=fsync status=none; done'
  echo "=== under load: two CPU hogs and a disk writer (pids ${load_pids[*]}) ==="
  timed "default tests" ctest --preset default --parallel "$test_jobs"
  stop_load
  trap - EXIT
  echo "tools/test.sh --under-load: the default tests passed"
  printf '  %s\n' "${timings[@]}"
  exit 0
fi

run_preset default "$test_jobs"
# The installed service as an operator meets it: Debian 12 booted with systemd as PID 1 under
# user-mode Linux, beside the one-job compile of the next presets (start_early_builds). Nothing
# else runs beside it: the CAN stage and the soaks wait (a second guest beside it made the
# stage's first travel end in a link fault). What a shared machine does to its guest (a lost
# timer event, a starved cycle) the stage handles itself (docs/operations.md).
if [ $systemd_stage = 1 ]; then
  echo "=== systemd stage: the package on Debian 12 with systemd as PID 1 (beside a one-job"
  echo "    compile of the next presets; its log: build/systemd-stage.log) ==="
  if [ -n "${rootfs_pid:-}" ]; then
    wait "$rootfs_pid" || { cat build/rootfs.log; echo "tools/test.sh: the root file system failed"; exit 1; }
    grep -h '^build-rootfs:' build/rootfs.log || true
  fi
  systemd_start=$SECONDS
  tests/systemd/stage.sh build >build/systemd-stage.log 2>&1 &
  systemd_pid=$!
  background+=("$systemd_pid")
  start_early_builds
  systemd_rc=0
  wait "$systemd_pid" || systemd_rc=$?
  stop_early_builds
  cat build/systemd-stage.log
  timings+=("$(printf '%-22s %5d s (beside a one-job compile)' "systemd stage" $((SECONDS - systemd_start)))")
  [ $systemd_rc = 0 ] || { echo "tools/test.sh: the systemd stage failed"; exit 1; }
fi
# The real-SocketCAN stage, then the soaks, beside the one-job nice-19 compile of the next
# presets (start_early_builds): each of them keeps a CPU busy at most (the guest's uniprocessor
# kernel; a soak's daemon mostly waits on its simulated car), so the other CPU builds meanwhile.
# Measured here: the compile got 5 of the 53 fuzz objects done during the CAN stage alone.
start_early_builds  # a failing stage ends the script, and its EXIT trap the builder
if [ "${LIFTD_SKIP_UML:-0}" != 1 ]; then
  # The tests that need a kernel with AF_CAN (label "vcan"), inside user-mode Linux.
  echo "=== real SocketCAN: user-mode Linux with vcan0 (beside a one-job compile of the next"
  echo "    presets; its log: build/early-builds.log) ==="
  timed "uml can" tools/uml/can-stage.sh build
fi
if [ "${LIFTD_SKIP_VM:-0}" != 1 ]; then
  # liftd on a real kernel's serial drivers (QEMU's 16550A and FTDI usb-serial) against the
  # drive simulator on the host. The one-job compile pauses meanwhile (ninja goes on where it
  # stopped): the guest's 15 ms cycle needs the CPUs the compiler would take.
  stop_early_builds
  echo "=== real UART: liftd in a QEMU guest on the 16550A and an FTDI USB adapter ==="
  timed "vm serial" tools/vm/serial-stage.sh build
  start_early_builds
fi
soak_seconds=${LIFTD_SOAK_SECONDS:-45}
if [ "$soak_seconds" != 0 ]; then
  # Every drive kind the build registered (LIFTD_DRIVE_KINDS, written to kinds.txt by the
  # configure run): DCP under the fault soak, the others under attack (floods, card reconnects,
  # fault flaps), each scenario several times: tools/soak --kind K runs tools/K-soak. A kind
  # without that file fails here, the file named.
  while read -r kind; do
    echo "=== soak $kind: $soak_seconds s ==="
    timed "soak $kind" tools/soak --kind "$kind" --seconds "$soak_seconds" --seed 1
  done <build/generated/drive/kinds.txt
fi
stop_early_builds
[ "${LIFTD_SKIP_ASAN:-0}" = 1 ] || run_preset asan "$asan_test_jobs" -LE 'slow|vcan'
if [ "${LIFTD_SKIP_FUZZ:-0}" != 1 ]; then
  echo "=== preset: fuzz ==="
  cmake --preset fuzz >/dev/null
  timed "fuzz build" cmake --build --preset fuzz --parallel "$jobs"
  timed "fuzz runs" ctest --preset fuzz --parallel "$jobs"  # one core per fuzz target
fi
echo "tools/test.sh: all presets passed"
printf '  %s\n' "${timings[@]}"
