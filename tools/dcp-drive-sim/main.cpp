// dcp-drive-sim: the simulated DCP drive on a serial device or pty at 38400 8N1, a command-line
// front end over dcp::sim::SerialDriveRunner (which finds frames by the inter-frame gap and answers
// them inside the DCP 7.2 window). Everything the drive does is printed; faults can be switched
// on stdin while it runs ("help" lists them). With --encoder it is also the shaft's absolute
// encoder on CAN: the simulated car's position, as a process beside liftd would get it from a
// real encoder (position.source "can").
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "can/frame.hpp"
#include "can/socket.hpp"
#include "common/mono_time.hpp"
#include "common/version.hpp"
#include "dcp/sim/serial_runner.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;
using liftd::dcp::sim::ReplyFault;
using liftd::dcp::sim::SerialDriveRunner;

volatile sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

struct Options {
  liftd::dcp::sim::DriveConfig config;
  liftd::dcp::sim::RunnerOptions runner;
  double status_interval_s = 0.0;
  std::string encoder;         ///< "unix:PATH" (listen there) or a CAN interface; empty: none
  long encoder_period_ms = 5;  ///< how often the encoder sends the position
};

// The encoder's frame: identifier 0x190 (position.can_id 400), the position in whole mm as four
// bytes little endian, two's complement from byte 0 (position.can_signed true, the other
// position.can_* keys at their defaults: offset 0, length 4, 1000 um per count, offset 0 mm).
constexpr std::uint32_t kEncoderId = 0x190;

liftd::can::Frame encoder_frame(double position_mm) {
  const auto count =
      static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(position_mm)));
  const std::array<std::uint8_t, 4> bytes = {
      static_cast<std::uint8_t>(count), static_cast<std::uint8_t>(count >> 8),
      static_cast<std::uint8_t>(count >> 16), static_cast<std::uint8_t>(count >> 24)};
  return liftd::can::make_frame(kEncoderId, bytes);
}

/// Sends the simulated car's position every period on its own thread: to whoever is connected
/// to a Unix endpoint (one reader at a time, the newest wins) or onto a CAN interface.
class EncoderSender {
 public:
  EncoderSender(const SerialDriveRunner& runner, std::chrono::milliseconds period)
      : runner_(runner), period_(period) {}
  ~EncoderSender() { stop(); }

  /// Opens the endpoint; the error text, or empty.
  std::string open(const std::string& endpoint) {
    if (endpoint.rfind("unix:", 0) == 0) {
      auto l = liftd::can::listen_unix(endpoint.substr(5));
      if (!l) return l.error().what + ": " + std::strerror(l.error().code);
      listener_ = l.value();
    } else {
      auto s = liftd::can::CanSocket::open(endpoint, {kEncoderId});
      if (!s) return s.error().what + ": " + std::strerror(s.error().code);
      peer_.emplace(std::move(s.value()));
    }
    thread_ = std::thread([this] { run(); });
    return {};
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (listener_ >= 0) ::close(listener_);
    listener_ = -1;
  }

 private:
  void run() {
    while (!stop_) {
      pollfd fd{listener_, POLLIN, 0};
      const int n = ::poll(&fd, listener_ >= 0 ? 1 : 0, static_cast<int>(period_.count()));
      if (n > 0 && (fd.revents & POLLIN) != 0) {
        const int c = ::accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (c >= 0) peer_.emplace(liftd::can::CanSocket::adopt(c, {kEncoderId}));
      }
      if (!peer_) continue;
      // What the reader sends is not for the encoder; reading it notices a reader that left.
      using Kind = liftd::can::Received::Kind;
      for (Kind kind = peer_->read().kind; kind != Kind::Nothing; kind = peer_->read().kind) {
        if (kind == Kind::Closed || kind == Kind::Failed) {
          if (listener_ >= 0) peer_.reset();  // a Unix reader left; an interface stays
          break;
        }
      }
      if (!peer_) continue;
      const double position = runner_.encoder_sample().position_at_mm(liftd::mono_now());
      const int err = peer_->write(encoder_frame(position));
      if (err != 0 && err != EAGAIN && err != ENOBUFS && listener_ >= 0) peer_.reset();
    }
  }

  const SerialDriveRunner& runner_;
  std::chrono::milliseconds period_;
  int listener_ = -1;
  std::optional<liftd::can::CanSocket> peer_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: dcp-drive-sim --device PATH [--dcp 3|4] [options]\n"
      "  --device PATH        serial device or pty slave (38400 8N1)\n"
      "  --dcp 3|4            DCP type answered in I0 (default 4)\n"
      "  --reply-delay-us N   reply delay after the frame's last byte (default 1000)\n"
      "  --gap-us N           gap inside a frame that resynchronises (default 1000)\n"
      "  --position-mm N      car position at start (default 0)\n"
      "  --maker XX           drive maker code in I0 (default KW)\n"
      "  --no-init            travel without a prior I0 exchange\n"
      "  --older-drive        ignore I1, answer I0 with odd version/date fields\n"
      "  --frames N           exit after N master frames\n"
      "  --status S           print a status line every S seconds\n"
      "  --reconnect          reopen a lost device instead of exiting\n"
      "  --echo               the line echoes: give the master each byte it sent back\n"
      "                       before the reply (as an auto-direction USB adapter does)\n"
      "  --quiet              print only start, faults and the summary\n"
      "  --encoder ENDPOINT   also be the shaft's absolute encoder on CAN: unix:PATH\n"
      "                       (listen there, as liftd's can.interface unix:PATH) or an\n"
      "                       interface (vcan0); id 0x190, 4 bytes little endian, signed,\n"
      "                       1 mm per count (position.can_signed true, the other\n"
      "                       position.can_* keys at their defaults)\n"
      "  --encoder-period-ms N  how often the encoder sends (default 5)\n"
      "stdin commands: fault|warn|notready on|off, badsum|s7|late|noreply|garbage N,\n"
      "  rate badsum|s7|late|noreply|garbage P, channel partial|garbage|silence,\n"
      "  clear, status, help\n");
}

bool parse(int argc, char** argv, Options& o) {
  o.runner.reconnect = false;  // the tool exits when its device goes, unless --reconnect
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--device" && (v = next())) {
      o.runner.device = v;
    } else if (a == "--dcp" && (v = next())) {
      if (std::strcmp(v, "3") == 0)
        o.config.protocol = liftd::dcp::Protocol::Dcp3;
      else if (std::strcmp(v, "4") == 0)
        o.config.protocol = liftd::dcp::Protocol::Dcp4;
      else
        return false;
    } else if (a == "--reply-delay-us" && (v = next())) {
      o.config.reply_delay = std::chrono::microseconds(std::strtol(v, nullptr, 10));
    } else if (a == "--gap-us" && (v = next())) {
      o.runner.gap = std::chrono::microseconds(std::strtol(v, nullptr, 10));
    } else if (a == "--position-mm" && (v = next())) {
      o.config.start_position_mm = std::strtoll(v, nullptr, 10);
    } else if (a == "--maker" && (v = next()) && std::strlen(v) == 2) {
      o.config.maker = {v[0], v[1]};
    } else if (a == "--older-drive") {
      o.config.older_drive = true;
    } else if (a == "--no-init") {
      o.config.require_init = false;
    } else if (a == "--frames" && (v = next())) {
      o.runner.max_frames = std::strtoull(v, nullptr, 10);
    } else if (a == "--status" && (v = next())) {
      o.status_interval_s = std::strtod(v, nullptr);
    } else if (a == "--reconnect") {
      o.runner.reconnect = true;
    } else if (a == "--echo") {
      o.runner.echo = true;
    } else if (a == "--quiet") {
      o.runner.quiet = true;
    } else if (a == "--encoder" && (v = next())) {
      o.encoder = v;
    } else if (a == "--encoder-period-ms" && (v = next())) {
      o.encoder_period_ms = std::strtol(v, nullptr, 10);
      if (o.encoder_period_ms < 1 || o.encoder_period_ms > 1000) return false;
    } else {
      return false;
    }
  }
  return !o.runner.device.empty();
}

// Applies one stdin command; returns false for an unknown one.
bool command(SerialDriveRunner& runner, const std::string& line) {
  std::istringstream in(line);
  std::string verb, arg;
  in >> verb >> arg;
  ReplyFault f{};
  liftd::dcp::sim::ChannelFault channel{};
  if (verb == "fault")
    runner.set_general_fault(arg == "on");
  else if (verb == "warn")
    runner.set_advance_warning(arg == "on");
  else if (verb == "notready")
    runner.set_not_ready(arg == "on");
  else if (verb == "clear")
    runner.clear_reply_faults();
  else if (verb == "status")
    std::printf("%s\n", liftd::dcp::sim::format_status(runner.status()).c_str());
  else if (verb == "channel" && liftd::dcp::sim::parse_channel_fault(arg, channel))
    runner.inject_channel(channel);
  else if (verb == "help")
    usage(stdout);
  else if (verb == "rate" && liftd::dcp::sim::parse_reply_fault(arg, f)) {
    double p = 0.0;
    in >> p;
    runner.set_fault_rate(f, p);
  } else if (liftd::dcp::sim::parse_reply_fault(verb, f)) {
    runner.inject(f, static_cast<std::uint32_t>(std::strtoul(arg.c_str(), nullptr, 10)));
  } else {
    return false;
  }
  return true;
}

void print_events(SerialDriveRunner& runner) {
  std::vector<std::string> lines;
  runner.drain_event_lines(lines);
  for (const auto& l : lines) std::printf("%s\n", l.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (!parse(argc, argv, opt)) {
    usage(stderr);
    return 2;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  SerialDriveRunner runner(opt.config, opt.runner);
  if (!runner.start()) {
    std::fprintf(stderr, "dcp-drive-sim: %s\n", runner.last_error().c_str());
    return 1;
  }
  std::printf("dcp-drive-sim %s: DCP%c drive on %s, reply delay %lld us%s\n",
              std::string(liftd::kVersion).c_str(),
              opt.config.protocol == liftd::dcp::Protocol::Dcp3 ? '3' : '4',
              opt.runner.device.c_str(), static_cast<long long>(opt.config.reply_delay.count()),
              runner.port_features().rs485_enabled ? ", kernel RS485" : "");
  // Only this thread reads the runner's encoder sample from here on (one reader, see there).
  EncoderSender encoder(runner, std::chrono::milliseconds(opt.encoder_period_ms));
  if (!opt.encoder.empty()) {
    if (const std::string error = encoder.open(opt.encoder); !error.empty()) {
      std::fprintf(stderr, "dcp-drive-sim: encoder %s: %s\n", opt.encoder.c_str(), error.c_str());
      runner.stop();
      return 1;
    }
    std::printf("dcp-drive-sim: encoder on %s, every %ld ms (id 0x%03X)\n", opt.encoder.c_str(),
                opt.encoder_period_ms, kEncoderId);
  }

  bool stdin_open = true;
  std::string pending_line;
  MonoTime next_status = liftd::mono_now();
  while (!g_stop && runner.running()) {
    // The runner serves the port on its own thread; this loop handles stdin and printing.
    pollfd in{STDIN_FILENO, POLLIN, 0};
    const int n = poll(&in, stdin_open ? 1 : 0, 20);
    if (stdin_open && n > 0 && (in.revents & (POLLIN | POLLHUP)) != 0) {
      char buf[256];
      const ssize_t got = read(STDIN_FILENO, buf, sizeof buf);
      if (got <= 0) {
        stdin_open = false;
      } else {
        pending_line.append(buf, static_cast<std::size_t>(got));
        std::size_t nl;
        while ((nl = pending_line.find('\n')) != std::string::npos) {
          const std::string line = pending_line.substr(0, nl);
          pending_line.erase(0, nl + 1);
          if (!line.empty() && !command(runner, line))
            std::printf("unknown command: %s\n", line.c_str());
        }
      }
    }
    print_events(runner);
    const MonoTime now = liftd::mono_now();
    if (opt.status_interval_s > 0 && now >= next_status) {
      std::printf("%s\n", liftd::dcp::sim::format_status(runner.status()).c_str());
      next_status = now + std::chrono::duration_cast<MonoTime>(
                              std::chrono::duration<double>(opt.status_interval_s));
    }
  }
  encoder.stop();
  runner.stop();
  print_events(runner);
  const auto s = runner.status();
  if (s.state == liftd::dcp::sim::RunnerState::DeviceLost)
    std::fprintf(stderr, "dcp-drive-sim: device lost\n");
  std::printf(
      "summary: frames %llu bad %llu replies %llu repeats %llu resyncs %llu travels %llu "
      "dropped-events %llu\n",
      static_cast<unsigned long long>(s.sim.frames),
      static_cast<unsigned long long>(s.sim.bad_frames),
      static_cast<unsigned long long>(s.sim.replies),
      static_cast<unsigned long long>(s.sim.repeats),
      static_cast<unsigned long long>(s.runner.resyncs),
      static_cast<unsigned long long>(s.sim.travels),
      static_cast<unsigned long long>(s.runner.dropped_events));
  return 0;
}
