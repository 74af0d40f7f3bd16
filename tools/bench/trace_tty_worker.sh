#!/usr/bin/env bash
# How long received tty bytes wait for the flip-buffer worker: every flush_to_ldisc work item
# from its queueing (tty_flip_buffer_push: a UART interrupt, or a pty write) to the moment a
# kernel worker starts it (ftrace workqueue_queue_work / workqueue_execute_start, own instance).
# Until it runs, the bytes are not in the line discipline: no reader, however real-time, sees
# them. Prints the distribution and the workers that ran it.
#   tools/bench/trace_tty_worker.sh [SECONDS]        (root)
set -euo pipefail
seconds=${1:-10}
tr=/sys/kernel/tracing
if [ ! -e "$tr/instances" ]; then
  tr=/tmp/liftd-tracefs
  mkdir -p "$tr"
  mountpoint -q "$tr" || mount -t tracefs nodev "$tr"
fi
inst=$tr/instances/liftd-tty-$$
mkdir "$inst"
trap 'echo 0 > "$inst/tracing_on"; rmdir "$inst" 2>/dev/null || true' EXIT
echo 0 >"$inst/tracing_on"
echo 16384 >"$inst/buffer_size_kb"
echo 1 >"$inst/events/workqueue/workqueue_queue_work/enable"
echo 1 >"$inst/events/workqueue/workqueue_execute_start/enable"
echo 1 >"$inst/tracing_on"
sleep "$seconds"
echo 0 >"$inst/tracing_on"
out=$(mktemp /tmp/liftd-ttywork-XXXXXX.txt)
grep flush_to_ldisc "$inst/trace" >"$out" || true
echo "raw trace: $out" >&2
python3 - "$out" <<'PY'
import re, sys, collections
queued = {}
waits = []
workers = collections.Counter()
for line in open(sys.argv[1]):
    m = re.match(r'\s*(.+?)-(\d+)\s+\[\d+\].*?\s(\d+\.\d+):\s+(workqueue_\w+):.*work struct[ =](\w+)', line)
    if not m:
        continue
    comm, t, ev, work = m.group(1), float(m.group(3)), m.group(4), m.group(5)
    if ev == 'workqueue_queue_work':
        queued.setdefault(work, t)
    elif ev == 'workqueue_execute_start' and work in queued:
        waits.append((t - queued.pop(work)) * 1e6)
        workers[comm] += 1
waits.sort()
if not waits:
    print('no flush_to_ldisc work seen'); sys.exit()
q = lambda f: waits[min(len(waits) - 1, int(f * len(waits)))]
print(f'flush_to_ldisc: {len(waits)} runs; queued -> started (us): p50 {q(0.5):.0f}  p99 {q(0.99):.0f}  '
      f'p99.9 {q(0.999):.0f}  max {waits[-1]:.0f}; over 10 ms: {sum(w > 10000 for w in waits)}')
print('run by:', ', '.join(f'{c} {n}' for c, n in workers.most_common(6)))
PY
