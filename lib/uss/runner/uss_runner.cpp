#include "uss/runner/uss_runner.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "uss/timing.hpp"

namespace liftd::uss {
namespace {

constexpr auto kIdleTick = std::chrono::milliseconds(5);  // hooks' pace while without port
// Longest single sleep: a long wait (fixed cycle time, A 5.1.1) is cut into slices so that
// stop() and a reopened port are seen and the watchdog progress keeps moving.
constexpr auto kMaxSleep = std::chrono::milliseconds(20);

std::size_t recorder_capacity(const UssRunnerConfig& config, const uss::Master& master) {
  // Each exchange writes the sent telegram and the reply (or missing) record.
  const auto per_pass = master.config().polling_list.size();
  const auto exchange = std::max<std::int64_t>(
      master.expected_cycle_time().count() / static_cast<std::int64_t>(per_pass > 0 ? per_pass : 1),
      std::chrono::nanoseconds(std::chrono::milliseconds(1)).count());
  const auto exchanges =
      static_cast<std::size_t>(std::max<std::int64_t>(config.recorder_span.count() / exchange, 1));
  return std::clamp<std::size_t>(2 * exchanges, 256, UssRunner::kMaxRecords);
}

// The USS link's note on a freshly opened port: whether the driver keeps line error counters
// (A 5.2.2 counts parity and framing errors; a pty keeps none).
void add_line_counter_note(const io::SerialPort& opened, std::string& text) {
  io::LineCounts counts;
  const int count_err = opened.line_counts(counts);
  text += count_err == 0
              ? ", line error counters available"
              : ", no line error counters (" + std::string(std::strerror(count_err)) + ")";
}

}  // namespace

io::SerialSettings uss_serial_settings(std::uint32_t baud) {
  io::SerialSettings s;
  s.baud = baud;
  s.data_bits = 8;              // A 6.1: start, 8 data, parity, stop = 11 bits
  s.parity = io::Parity::Even;  // B: even parity
  s.stop_bits = 1;
  s.mark_errors = true;  // A 5.2.2: parity and framing errors are counted
  return s;
}

UssRunner::UssRunner(UssRunnerConfig config, uss::Master& master, UssHooks& hooks)
    : config_(std::move(config)),
      master_(master),
      hooks_(hooks),
      input_check_(io::character_time(config_.serial)),
      echo_(config_.echo),
      recorder_(recorder_capacity(config_, master), config_.recorder_bytes),
      port_keeper_(rt::PortKeeperConfig{config_.device_path, config_.serial,
                                        config_.reopen_backoff_min, config_.reopen_backoff_max,
                                        add_line_counter_note}) {
  echo_state_.store(echo_.state(), std::memory_order_relaxed);
  if (config_.serial.baud != master_.config().baud) {
    throw std::invalid_argument("uss runner: the line runs at " +
                                std::to_string(config_.serial.baud) + " baud, the master at " +
                                std::to_string(master_.config().baud) +
                                " (the timing rules of A 5 and A 6 follow the baud rate)");
  }
}

UssRunner::~UssRunner() {
  stop();
}

int UssRunner::start() {
  rt::RtThreadOptions options = config_.thread;
  if (options.name.empty()) options.name = "liftd-uss-bus";  // ps -L, chrt -p, ftrace
  return port_keeper_.start(options, [this] { loop(); });
}

void UssRunner::stop() noexcept {
  port_keeper_.stop();
}

bool UssRunner::poll_event(rt::CycleEvent& out) noexcept {
  return bus_events_.try_pop(out) || port_keeper_.poll_event(out);
}

UssRunnerStats UssRunner::stats() const {
  UssRunnerStats s;
  auto get = [](const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  s.counters.exchanges = get(counters_.exchanges);
  s.counters.good_replies = get(counters_.good_replies);
  s.counters.bad_replies = get(counters_.bad_replies);
  s.counters.reply_timeouts = get(counters_.reply_timeouts);
  s.counters.no_reply_expected = get(counters_.no_reply_expected);
  s.counters.cycles = get(counters_.cycles);
  s.counters.port_losses = port_keeper_.port_losses();
  s.counters.port_opens = port_keeper_.port_opens();
  s.counters.send_failures = get(counters_.send_failures);
  s.counters.stray_bytes = get(counters_.stray_bytes);
  s.counters.chars_received = get(counters_.chars_received);
  s.counters.line_errors = get(counters_.line_errors);
  s.counters.echo_collisions = get(counters_.echo_collisions);
  s.cycle_time = cycle_time_.copy();
  s.wake_lateness = wake_lateness_.copy();
  s.reply_time = reply_time_.copy();
  return s;
}

void UssRunner::notify() noexcept {
  if (notify_fd_ < 0) return;
  const std::uint64_t one = 1;
  // eventfd, non-blocking: EAGAIN only if the counter were near 2^64 (never in practice).
  [[maybe_unused]] const ssize_t n = ::write(notify_fd_, &one, sizeof one);
}

void UssRunner::adopt_offered_port() noexcept {
  if (!port_keeper_.adopt_offered_port()) return;
  decoder_.reset();
  echo_.port_opened();  // another adapter may stand behind the name now
  echo_state_.store(echo_.state(), std::memory_order_relaxed);
  const MonoTime now = mono_now();
  // The line state is unknown: a full start pause before the first telegram (A 5.1.2).
  master_.reset_link(now);
  hooks_.on_port(true, now);
}

void UssRunner::loop() noexcept {
  while (!port_keeper_.stop_requested()) {
    held_loss_.retry(bus_events_);
    adopt_offered_port();
    if (!port_keeper_.port().is_open()) {
      rt::sleep_until(mono_now() + kIdleTick);
      hooks_.after_exchange(mono_now());
    } else {
      // A 5.1.2 start pause, A 5.1.1 fixed cycle time: the master says when.
      const MonoTime at = master_.send_at();
      const MonoTime now = mono_now();
      if (at > now + kMaxSleep) {
        rt::sleep_until(now + kMaxSleep);
        progress_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (at > now) {
        rt::sleep_until(at);
        // Wake-up lateness of a sleep, as the reference loops measure it. After a reply
        // timeout send_at() is already past (the line has been free since our request ended,
        // A 5.1.2): sending at once is then the rule, not a late wake-up.
        wake_lateness_.record(mono_now() - at);
      }
      const MonoTime wake = mono_now();
      run_exchange(wake);
      const MonoTime done = mono_now();
      if (const std::uint64_t cycles = master_.cycles(); cycles != last_cycles_) {
        last_cycles_ = cycles;
        bump(counters_.cycles);
        cycle_time_.record(master_.last_cycle_time());
      }
      hooks_.after_exchange(done);
    }
    progress_.fetch_add(1, std::memory_order_relaxed);
    notify();
  }
}

void UssRunner::run_exchange(MonoTime wake) noexcept {
  // Anything still queued is stray (a late reply, line noise): not part of the next reply.
  // After a good reply it is only what the line discipline holds: read away. After a timeout or
  // a bad reply the rest may sit in the flip buffer, where only TCFLSH reaches it; TCFLSH takes
  // the flip buffer's lock, which the tty's worker holds while it delivers, so only then.
  io::SerialPort& port = port_keeper_.port();
  const io::IoResult flushed = stray_possible_ ? port.flush_queued() : port.drain_queued();
  stray_possible_ = false;
  if (flushed.status == io::IoStatus::DeviceLost) {
    lose_port(wake, flushed.error_number);
    return;
  }
  bump(counters_.stray_bytes, flushed.bytes);
  decoder_.reset();
  const MonoTime sent_at = mono_now();
  const std::span<const std::uint8_t> telegram = master_.next_telegram(sent_at);
  if (telegram.empty()) return;
  const io::IoResult written = port.write_frame(telegram);
  // The UART sends in the background: the last bit leaves the line after n character times
  // (A 6.2); on a pty this is what keeps the reply delay and the next start pause honest.
  const MonoTime end = sent_at + uss::transmission_time(master_.config().baud, telegram.size());
  if (written.status == io::IoStatus::DeviceLost) {
    recorder_.record(sent_at, rt::Direction::Tx, rt::record_flag::kSendFailed, telegram);
    lose_port(sent_at, written.error_number);
    return;
  }
  if (written.status == io::IoStatus::Ok) {
    recorder_.record(sent_at, rt::Direction::Tx, rt::record_flag::kSent, telegram);
  } else {
    // The port refused (part of) the telegram: the reply supervision still runs (it will
    // time out), so the slave is flagged as A 5.2.1.1 says.
    bump(counters_.send_failures);
    recorder_.record(sent_at, rt::Direction::Tx, rt::record_flag::kSendFailed, telegram);
  }
  master_.on_sent(end);
  sent_end_ = end;
  echo_sent_ = telegram;
  echo_pos_ = 0;
  held_ = 0;
  echo_candidate_ = false;
  echo_ambiguous_ = false;
  echo_done_ = !echo_.expected() && !echo_.undecided();
  receive(sent_at);
}

void UssRunner::feed(std::size_t raw_bytes, MonoTime now) noexcept {
  const std::span<const std::uint8_t> raw(raw_.data(), raw_bytes);
  std::size_t count = 0;
  if (config_.serial.mark_errors) {
    count = decoder_.decode(raw, chars_);
  } else {
    for (const std::uint8_t b : raw) chars_[count++] = uss::RxChar{b, uss::LineError::None};
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!master_.awaiting_reply()) break;  // the rest is stray, flushed before the next send
    if (!echo_done_ && take_echo(chars_[i], now)) continue;
    to_master(chars_[i], now);
  }
}

void UssRunner::to_master(const uss::RxChar& c, MonoTime at) noexcept {
  bump(counters_.chars_received);
  if (c.error != uss::LineError::None) bump(counters_.line_errors);
  if (rx_record_size_ < rx_record_.size()) rx_record_[rx_record_size_++] = c.byte;
  master_.on_char(c, at);
}

bool UssRunner::take_echo(const uss::RxChar& c, MonoTime at) noexcept {
  const bool same = c.error == uss::LineError::None && echo_pos_ < echo_sent_.size() &&
                    c.byte == echo_sent_[echo_pos_];
  if (echo_.expected()) {
    if (!same) {
      // Our telegram came back changed: another station drove the bus while we sent. The
      // slave did not receive it intact (A 5.2.2); whatever follows is no reply to it.
      echo_done_ = true;
      bump(counters_.echo_collisions);
      if (c.error != uss::LineError::None) bump(counters_.line_errors);
      master_.on_collision(at);
      return true;
    }
    echo_done_ = ++echo_pos_ == echo_sent_.size();
    return true;
  }
  // Auto, still finding out: hold what matches the telegram so far.
  if (same) {
    held_at_[held_++] = at;
    if (++echo_pos_ == echo_sent_.size()) {
      echo_done_ = true;
      echo_candidate_ = true;  // all of it came back: the echo, unless nothing follows
    }
    return true;
  }
  echo_done_ = true;  // no echo this time: what was held is the reply's start
  release_held();
  return false;
}

void UssRunner::release_held() noexcept {
  const std::size_t n = held_;
  held_ = 0;
  echo_candidate_ = false;
  for (std::size_t j = 0; j < n && master_.awaiting_reply(); ++j) {
    to_master(uss::RxChar{echo_sent_[j], uss::LineError::None}, held_at_[j]);
  }
}

void UssRunner::after_reply_window() noexcept {
  // The master's deadline has come with characters held back. Part of the telegram is no
  // echo (an echo comes back whole): the reply's start. A whole copy of a poll is the echo
  // of a slave that is silent. A whole copy of a mirror telegram (A 5.3) is the echo or the
  // mirror reply, and nobody can tell: when it came says nothing either (a USB adapter delivers
  // the echo late, a simulated slave on a pty answers before our telegram would have left the
  // wire). Taken as the reply, it decides nothing; an echoing bus whose slave is silent passes
  // that one start mirror, and its polls then find the slave silent.
  if (held_ == 0) return;
  if (echo_candidate_ && master_.last_kind() != uss::TelegramKind::Mirror) return;
  echo_ambiguous_ = echo_candidate_;
  echo_done_ = true;
  release_held();
}

void UssRunner::note_echo_decided(MonoTime now) noexcept {
  const io::EchoState state = echo_.state();
  echo_state_.store(state, std::memory_order_relaxed);
  rt::CycleEvent e;
  e.kind = rt::CycleEventKind::LineEcho;
  e.time = now;
  e.count = state == io::EchoState::Present ? 1 : 0;
  (void)bus_events_.try_push(e);  // once per port open; a full queue loses it (echo_state())
}

void UssRunner::receive(MonoTime sent_at) noexcept {
  io::SerialPort& port = port_keeper_.port();
  rx_record_size_ = 0;
  MonoTime now = sent_at;
  while (master_.awaiting_reply()) {
    // Read first: characters already queued count even if this thread woke late. Only what the
    // line discipline holds: read(2) and poll(2) on an empty tty wait for the flip-buffer
    // worker, a normal-priority kernel thread (docs/architecture.md, "What the cycle may wait
    // for").
    const io::IoResult got = port.read_queued(raw_);
    now = mono_now();
    if (got.bytes > 0) feed(got.bytes, now);
    if (got.status == io::IoStatus::DeviceLost) {
      lose_port(now, got.error_number);
      return;
    }
    if (got.bytes > 0) continue;
    if (now >= master_.deadline()) {
      after_reply_window();
      master_.on_time(now);
      continue;
    }
    // Look every character time (A 6.1): a character is stamped at most one late.
    const io::IoResult waited = port.wait_queued(master_.deadline(), input_check_);
    if (waited.status == io::IoStatus::DeviceLost) {
      lose_port(mono_now(), waited.error_number);
      return;
    }
    if (port_keeper_.stop_requested()) {
      master_.reset_link(mono_now());
      return;
    }
  }
  bump(counters_.exchanges);
  if (master_.last_outcome() == uss::ExchangeOutcome::Reply && !echo_ambiguous_ &&
      echo_.good_reply_seen(echo_candidate_)) {
    note_echo_decided(now);
  }
  stray_possible_ = master_.last_outcome() == uss::ExchangeOutcome::Timeout ||
                    master_.last_outcome() == uss::ExchangeOutcome::BadReply;
  const std::span<const std::uint8_t> reply(rx_record_.data(), rx_record_size_);
  switch (master_.last_outcome()) {
    case uss::ExchangeOutcome::Reply:
      bump(counters_.good_replies);
      reply_time_.record(now - sent_end_);
      recorder_.record(now, rt::Direction::Rx, rt::record_flag::kReply, reply);
      break;
    case uss::ExchangeOutcome::BadReply:
      bump(counters_.bad_replies);
      recorder_.record(now, rt::Direction::Rx, rt::record_flag::kReply | rt::record_flag::kBad,
                       reply);
      break;
    case uss::ExchangeOutcome::Timeout:
      bump(counters_.reply_timeouts);
      recorder_.record(now, rt::Direction::Rx,
                       reply.empty() ? rt::record_flag::kMissing
                                     : rt::record_flag::kMissing | rt::record_flag::kPartial,
                       reply);
      break;
    case uss::ExchangeOutcome::NoReplyExpected:
      bump(counters_.no_reply_expected);
      break;
    case uss::ExchangeOutcome::None:
    case uss::ExchangeOutcome::Abandoned:
      break;
  }
}

void UssRunner::lose_port(MonoTime now, int error_number) noexcept {
  port_keeper_.hand_back_port();
  recorder_.record(now, rt::Direction::Event, rt::record_flag::kPortLost, {});
  master_.reset_link(now);
  held_loss_.push(bus_events_, rt::port_lost_event(now, error_number));
  hooks_.on_port(false, now);
}

}  // namespace liftd::uss
