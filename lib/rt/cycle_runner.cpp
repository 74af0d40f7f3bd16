#include "rt/cycle_runner.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace liftd::rt {
namespace {

std::size_t recorder_capacity(const CycleConfig& config) {
  const auto period = std::max<std::int64_t>(config.period.count(), 1);
  const auto cycles =
      static_cast<std::size_t>(std::max<std::int64_t>(config.recorder_span.count() / period, 1));
  // Each cycle writes a sent frame and a reply (or missing) record.
  return 2 * cycles;
}

}  // namespace

CycleRunner::CycleRunner(CycleConfig config, CycleEngine& engine)
    : config_(std::move(config)),
      engine_(engine),
      input_check_(config_.input_check_interval.count() > 0 ? config_.input_check_interval
                                                            : io::character_time(config_.serial)),
      echo_(config_.echo),
      reply_watch_(config_.reply_earliest_start +
                       input_check_ * static_cast<std::int64_t>(engine_.reply_size()),
                   config_.reply_latest_start +
                       input_check_ * static_cast<std::int64_t>(engine_.reply_size())),
      recorder_(recorder_capacity(config_), config_.recorder_bytes),
      port_keeper_(PortKeeperConfig{config_.device_path,
                                    config_.serial,
                                    config_.reopen_backoff_min,
                                    config_.reopen_backoff_max,
                                    {}}) {
  const auto max = max_send_window(config_.period, config_.reply_deadline);
  if (config_.send_window.count() < 0 || config_.send_window > max) {
    throw std::invalid_argument(
        "cycle send window " + std::to_string(config_.send_window.count() / 1000) +
        " us is out of range: allowed 0.." + std::to_string(max.count() / 1000) +
        " us (period minus reply deadline, DCP 7.2)");
  }
}

CycleRunner::~CycleRunner() {
  stop();
}

int CycleRunner::start() {
  RtThreadOptions options = config_.thread;
  if (options.name.empty()) options.name = "liftd-cycle";  // ps -L, chrt -p, ftrace
  return port_keeper_.start(options, [this] { cycle_loop(); });
}

void CycleRunner::stop() noexcept {
  port_keeper_.stop();
}

bool CycleRunner::poll_event(CycleEvent& out) noexcept {
  return cycle_events_.try_pop(out) || port_keeper_.poll_event(out);
}

CycleStats CycleRunner::stats() const {
  CycleStats s;
  auto get = [](const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  s.counters.cycles = get(counters_.cycles);
  s.counters.frames_sent = get(counters_.frames_sent);
  s.counters.good_replies = get(counters_.good_replies);
  s.counters.bad_replies = get(counters_.bad_replies);
  s.counters.missing_replies = get(counters_.missing_replies);
  s.counters.partial_replies = get(counters_.partial_replies);
  s.counters.late_sends = get(counters_.late_sends);
  s.counters.overruns = get(counters_.overruns);
  s.counters.skipped_cycles = get(counters_.skipped_cycles);
  s.counters.late_replies = get(counters_.late_replies);
  s.counters.port_losses = port_keeper_.port_losses();
  s.counters.port_opens = port_keeper_.port_opens();
  s.counters.send_failures = get(counters_.send_failures);
  s.counters.stray_bytes = get(counters_.stray_bytes);
  s.counters.echo_collisions = get(counters_.echo_collisions);
  s.counters.reply_looks = get(counters_.reply_looks);
  s.wake_lateness = wake_lateness_.copy();
  s.reply_latency = reply_latency_.copy();
  s.work_time = work_time_.copy();
  return s;
}

void CycleRunner::cycle_loop() noexcept {
  MonoTime next = mono_now() + config_.period;
  while (!port_keeper_.stop_requested()) {
    sleep_until(next);
    held_loss_.retry(cycle_events_);
    const MonoTime wake = mono_now();
    const auto late = wake - next;
    wake_lateness_.record(late);
    const WakeDecision d = decide_wake(late, config_.send_window, config_.period);
    if (d.send) {
      // Within the window (DCP 7.2 slack): send now, even if late; the reply deadline in
      // run_one_cycle still ends by the next planned start.
      if (d.late) bump(counters_.late_sends);
      end_skip_run(wake);
      run_one_cycle(wake, next);
      work_time_.record(mono_now() - wake);
      bump(counters_.cycles);
      next += config_.period;
    } else {
      // Too late to send without risking a collision: skip this cycle and every period that
      // has already begun, and keep the absolute schedule.
      bump(counters_.overruns);
      bump(counters_.skipped_cycles, d.skipped);
      recorder_.record(wake, Direction::Event, record_flag::kSkipped, {});
      note_skip(wake, late, d.skipped);
      next += config_.period * static_cast<std::int64_t>(d.skipped);
    }
    progress_.fetch_add(1, std::memory_order_relaxed);
    notify();
  }
}

void CycleRunner::note_skip(MonoTime now, std::chrono::nanoseconds lateness,
                            std::uint64_t skipped) noexcept {
  if (!in_skip_run_) {
    in_skip_run_ = true;
    run_skipped_ = 0;
    run_worst_ = lateness;
    run_started_ = now;
    skip_start_pending_ = true;
  }
  run_skipped_ += skipped;
  run_worst_ = std::max(run_worst_, lateness);
  if (skip_start_pending_) {
    CycleEvent e;
    e.kind = CycleEventKind::SkipRunStarted;
    e.time = run_started_;
    e.count = run_skipped_;
    e.lateness = run_worst_;
    if (push_skip_event(e)) skip_start_pending_ = false;
  }
}

void CycleRunner::end_skip_run(MonoTime now) noexcept {
  if (in_skip_run_) {
    in_skip_run_ = false;
    // The summary replaces a start event that never fitted (the queue was full).
    skip_start_pending_ = false;
    pending_end_ = CycleEvent{};
    pending_end_.kind = CycleEventKind::SkipRunEnded;
    pending_end_.time = now;
    pending_end_.count = run_skipped_;
    pending_end_.lateness = run_worst_;
    skip_end_pending_ = true;
  }
  if (skip_end_pending_ && push_skip_event(pending_end_)) skip_end_pending_ = false;
}

bool CycleRunner::push_skip_event(const CycleEvent& e) noexcept {
  // The last slots stay free for port losses: skip runs a slow reader has not taken yet must
  // not crowd out the loss of the port. A skip event that finds no room stays pending.
  if (cycle_events_.size_approx() + kSlotsKeptForLosses >= kEventSlots) return false;
  return cycle_events_.try_push(e);
}

void CycleRunner::notify() noexcept {
  if (notify_fd_ < 0) return;
  const std::uint64_t one = 1;
  // eventfd, non-blocking: EAGAIN only if the counter were near 2^64 (never in practice).
  [[maybe_unused]] const ssize_t n = ::write(notify_fd_, &one, sizeof one);
}

void CycleRunner::run_one_cycle(MonoTime wake, MonoTime planned) noexcept {
  io::SerialPort& port = port_keeper_.port();
  if (port_keeper_.adopt_offered_port()) {
    echo_.port_opened();  // another adapter may stand behind the name now
    reply_watch_.forget();
    echo_state_.store(echo_.state(), std::memory_order_relaxed);
    engine_.on_port_ready(wake);
  }
  if (port.is_open()) {
    // Stray bytes (a reply after its deadline, noise) must not be taken for this frame's reply.
    // After a good reply none can be on their way: read away what the line discipline holds.
    // After a missing or bad one the rest of it may still sit in the flip buffer, where only
    // TCFLSH reaches it; TCFLSH takes the flip buffer's lock, which the tty's worker holds while
    // it delivers, so it is used only then (docs/architecture.md).
    const io::IoResult flushed = stray_possible_ ? port.flush_queued() : port.drain_queued();
    stray_possible_ = false;
    if (flushed.status == io::IoStatus::DeviceLost) {
      lose_port(wake, flushed.error_number);
    } else {
      bump(counters_.stray_bytes, flushed.bytes);
      const std::span<const std::uint8_t> frame = engine_.frame_to_send(wake);
      if (!frame.empty()) {
        const MonoTime sent_at = mono_now();
        const io::IoResult written = port.write_frame(frame);
        if (written.status == io::IoStatus::Ok) {
          bump(counters_.frames_sent);
          recorder_.record(sent_at, Direction::Tx, record_flag::kSent, frame);
          const MonoTime deadline =
              std::min(sent_at + config_.reply_deadline, planned + config_.period);
          const std::uint64_t looks_before = port.looks();
          const Exchange x = read_reply(port, frame, sent_at, deadline);
          bump(counters_.reply_looks, port.looks() - looks_before);
          const io::IoResult& got = x.got;
          const std::span<const std::uint8_t> reply = x.reply;
          const MonoTime complete_by = x.complete_by;
          const MonoTime now = mono_now();
          const auto partial = reply;
          // DCP 7.2/7.3: a reply not complete by the deadline is lost. If only a look after the
          // deadline found it complete (this thread was held up, or it came in the last
          // character time), nobody can tell when it completed: count it as missing, never as
          // a good reply.
          const bool seen_late = got.status == io::IoStatus::Timeout &&
                                 reply.size() == std::min(engine_.reply_size(), kMaxReply);
          if (seen_late) bump(counters_.late_replies);
          if (x.collision && got.status != io::IoStatus::DeviceLost) {
            // The frame came back changed: another station drove the line while we sent, and
            // the drive cannot have read our frame intact. A bad reply (DCP 6.1 a), whatever
            // followed; its rest may still be on its way.
            bump(counters_.echo_collisions);
            bump(counters_.bad_replies);
            stray_possible_ = true;
            recorder_.record(now, Direction::Rx, record_flag::kReply | record_flag::kBad,
                             std::span<const std::uint8_t>(reply_.data(), got.bytes));
            reply_watch_.note_no_reply();
            engine_.on_bad_reply(now);
          } else if (got.status == io::IoStatus::Ok && !seen_late) {
            // From the look that found it complete: a stall of this thread after it is not
            // the drive's latency (and would put an accepted reply past its deadline).
            reply_latency_.record(complete_by - sent_at);
            reply_watch_.note_complete(complete_by - sent_at);
            const bool good = engine_.on_reply(reply, now);
            bump(good ? counters_.good_replies : counters_.bad_replies);
            if (good && echo_.good_reply_seen(x.echoed)) note_echo_decided(now);
            stray_possible_ = !good;
            recorder_.record(now, Direction::Rx,
                             good ? record_flag::kReply : record_flag::kReply | record_flag::kBad,
                             reply);
          } else if (got.status == io::IoStatus::DeviceLost) {
            if (got.bytes > 0) {
              recorder_.record(now, Direction::Rx, record_flag::kMissing | record_flag::kPartial,
                               partial);
            }
            lose_port(now, got.error_number);
          } else {
            stray_possible_ = true;  // the reply (or its rest) may still be on its way
            bump(counters_.missing_replies);
            std::uint8_t flags = record_flag::kMissing;
            if (!reply.empty() && !seen_late) {  // reply bytes, not just our frame's echo
              bump(counters_.partial_replies);
              flags |= record_flag::kPartial;
            }
            recorder_.record(now, Direction::Rx, flags, partial);
            reply_watch_.note_no_reply();
            engine_.on_no_reply(now);
          }
        } else if (written.status == io::IoStatus::DeviceLost) {
          recorder_.record(sent_at, Direction::Tx, record_flag::kSendFailed, frame);
          lose_port(sent_at, written.error_number);
        } else {
          bump(counters_.send_failures);
          bump(counters_.missing_replies);
          recorder_.record(sent_at, Direction::Tx, record_flag::kSendFailed, frame);
          engine_.on_no_reply(mono_now());
        }
      }
    }
  }
  engine_.after_cycle(mono_now());
}

CycleRunner::Exchange CycleRunner::read_reply(io::SerialPort& port,
                                              std::span<const std::uint8_t> frame, MonoTime sent_at,
                                              MonoTime deadline) noexcept {
  // Never read(2) or poll(2) an empty tty: both wait for the flip-buffer worker, a
  // normal-priority kernel thread (docs/architecture.md, "What the cycle may wait for"). Look
  // at what the line discipline holds instead: first when this drive's replies are usually
  // complete (never before DCP 7.2 lets one be, rt/reply_watch.hpp), then each time the bytes
  // still missing could all be there (SerialPort::read_queued_until: as many character times
  // as bytes missing). An echo of our frame comes back while we send, so it moves neither.
  Exchange x;
  const std::size_t size = std::min(engine_.reply_size(), kMaxReply);
  const std::size_t sent = std::min(frame.size(), kMaxReply);
  const MonoTime first_look = sent_at + reply_watch_.first_look();
  if (!echo_.expected() && !echo_.undecided()) {
    // No echo: the first byte read is the reply's.
    const std::span<std::uint8_t> reply(reply_.data(), size);
    x.got = port.read_queued_until(reply, deadline, input_check_, &x.complete_by, first_look);
    x.reply = reply.first(x.got.bytes);
    return x;
  }
  if (echo_.expected()) {
    // The echo, then the reply, both by the deadline (it counts from our frame's start).
    const std::span<std::uint8_t> all(reply_.data(), sent + size);
    x.got = port.read_queued_until(all, deadline, input_check_, &x.complete_by, first_look);
    const std::span<const std::uint8_t> read = all.first(x.got.bytes);
    x.collision = io::check_echo(frame.first(sent), read) == io::EchoCheck::Collision;
    x.echoed = true;
    x.reply = x.got.bytes > sent ? read.subspan(sent) : std::span<const std::uint8_t>{};
    return x;
  }
  // Auto, undecided: a reply's worth first. If it does not start as our frame's copy, it is
  // the reply (no echo). If it does, it is the copy, or the start of it, and the reply follows
  // (a copy alone is no reply: an echoing line with a silent drive gives just that).
  const std::span<std::uint8_t> first(reply_.data(), size);
  x.got = port.read_queued_until(first, deadline, input_check_, &x.complete_by, first_look);
  const std::span<const std::uint8_t> read = first.first(x.got.bytes);
  if (io::check_echo(frame.first(sent), read) == io::EchoCheck::Collision ||
      x.got.status != io::IoStatus::Ok) {
    x.reply = read;
    return x;
  }
  const std::span<std::uint8_t> rest(reply_.data() + size, sent);
  const io::IoResult more = port.read_queued_until(rest, deadline, input_check_, &x.complete_by);
  x.got = io::IoResult{more.status, size + more.bytes, more.error_number};
  x.echoed = true;
  x.reply = std::span<const std::uint8_t>(reply_.data() + sent, x.got.bytes - sent);
  return x;
}

void CycleRunner::note_echo_decided(MonoTime now) noexcept {
  const io::EchoState state = echo_.state();
  echo_state_.store(state, std::memory_order_relaxed);
  CycleEvent e;
  e.kind = CycleEventKind::LineEcho;
  e.time = now;
  e.count = state == io::EchoState::Present ? 1 : 0;
  // Rare (once per port open): it shares the queue with the skip events; a full queue loses it
  // (the state stays readable through echo_state()).
  (void)cycle_events_.try_push(e);
}

void CycleRunner::lose_port(MonoTime now, int error_number) noexcept {
  port_keeper_.hand_back_port();
  recorder_.record(now, Direction::Event, record_flag::kPortLost, {});
  held_loss_.push(cycle_events_, port_lost_event(now, error_number));
  engine_.on_port_lost(now);
}

}  // namespace liftd::rt
