#!/usr/bin/env bash
# Where a real-time thread blocks, from the kernel's own tracing (ftrace, no extra package):
# every time thread TID leaves the CPU (sched_switch with prev_pid == TID) the kernel stack is
# recorded, and the time until it runs again (sched_switch with next_pid == TID) is how long it
# waited there. Prints, per distinct blocking stack, how often and how long (total, worst).
# Uses its own trace instance, so it does not disturb other tracing on the machine.
#   tools/bench/trace_rt_blocking.sh TID [SECONDS]        (root; tracefs mounted or mountable)
# Sleeps the loop asks for (hrtimer_nanosleep / clock_nanosleep) are listed like any other wait:
# they are the waits it is meant to have.
set -euo pipefail
tid=$1
seconds=${2:-10}
tr=/sys/kernel/tracing
if [ ! -e "$tr/instances" ]; then
  tr=/tmp/liftd-tracefs
  mkdir -p "$tr"
  mountpoint -q "$tr" || mount -t tracefs nodev "$tr"
fi
inst=$tr/instances/liftd-rt-$$
mkdir "$inst"
trap 'echo 0 > "$inst/tracing_on"; rmdir "$inst" 2>/dev/null || true' EXIT
echo 0 >"$inst/tracing_on"
echo 16384 >"$inst/buffer_size_kb"
echo "prev_pid == $tid || next_pid == $tid" >"$inst/events/sched/sched_switch/filter"
echo "stacktrace if prev_pid == $tid" >"$inst/events/sched/sched_switch/trigger"
echo "pid == $tid" >"$inst/events/sched/sched_wakeup/filter"
echo 1 >"$inst/events/sched/sched_switch/enable"
echo 1 >"$inst/events/sched/sched_wakeup/enable"
echo 1 >"$inst/tracing_on"
sleep "$seconds"
echo 0 >"$inst/tracing_on"
out=$(mktemp /tmp/liftd-trace-XXXXXX.txt)
cat "$inst/trace" >"$out"
echo "raw trace: $out" >&2
python3 - "$out" "$tid" <<'PY'
import re, sys, collections
path, tid = sys.argv[1], sys.argv[2]
ts_re = re.compile(r'\s(\d+\.\d+):\s')
stats = collections.defaultdict(lambda: [0, 0.0, 0.0])  # count, total us, worst us
wakers = collections.Counter()
pending = None   # (time, stack key) of the last switch-out
stack = None
lines = open(path).read().splitlines()
i = 0
def key_of(frames):
    # The frames that say why: skip the scheduler's own.
    skip = ('__schedule', 'schedule', 'schedule_preempt_disabled', 'schedule_timeout',
            'preempt_schedule', '__traceiter', 'trace_', 'stack_trace')
    keep = [f for f in frames if not f.startswith(skip)]
    return ' <- '.join(keep[:7])
while i < len(lines):
    line = lines[i]
    m = ts_re.search(line)
    if 'sched_switch:' in line and m:
        t = float(m.group(1))
        if f'prev_pid={tid} ' in line:
            frames = []
            j = i + 1
            if j < len(lines) and '<stack trace>' in lines[j]:
                j += 1
                while j < len(lines) and lines[j].lstrip().startswith('=>'):
                    frames.append(lines[j].split('=>', 1)[1].strip().split('+')[0])
                    j += 1
            state = re.search(r'prev_state=(\S+)', line).group(1)
            pending = (t, f'[{state}] ' + key_of(frames))
            i = j
            continue
        if f'next_pid={tid} ' in line and pending:
            d = (t - pending[0]) * 1e6
            s = stats[pending[1]]
            s[0] += 1; s[1] += d; s[2] = max(s[2], d)
            pending = None
    elif 'sched_wakeup:' in line:
        w = re.match(r'\s*(.+?)-(\d+)\s+\[', line)
        wakers[w.group(1) if w else '?'] += 1
    i += 1
print(f'thread {tid}: where it left the CPU, how often, how long until it ran again (us)')
for k, (n, total, worst) in sorted(stats.items(), key=lambda kv: -kv[1][2]):
    print(f'{n:7d}  total {total:10.0f}  worst {worst:8.0f}  {k}')
print('woken by (comm of the waker):', ', '.join(f'{c} {n}' for c, n in wakers.most_common(8)))
PY
