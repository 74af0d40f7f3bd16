// dcp-drive-sim: the simulated DCP drive (lib/sim) on a serial device or pty at 38400 8N1.
// Frames are found by the inter-frame gap, answered inside the DCP 7.2 window, and everything
// the drive does is printed. Faults can be switched on stdin while it runs ("help" lists them).
#include <poll.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "common/mono_time.hpp"
#include "common/version.hpp"
#include "io/serial_port.hpp"
#include "sim/drive_sim.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;
using liftd::sim::DriveSim;
using liftd::sim::ReplyFault;
using liftd::sim::SimEvent;

volatile sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

struct Options {
  std::string device;
  liftd::sim::DriveConfig config;
  std::chrono::microseconds gap{1000};  // resynchronise after a gap this long inside a frame
  std::uint64_t max_frames = 0;         // 0 = run until a signal
  double status_interval_s = 0.0;
  bool quiet = false;
};

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: dcp-drive-sim --device PATH [--dcp 3|4] [options]\n"
               "  --device PATH        serial device or pty slave (38400 8N1)\n"
               "  --dcp 3|4            DCP type answered in I0 (default 4)\n"
               "  --reply-delay-us N   reply delay after the frame's last byte (default 1000)\n"
               "  --gap-us N           gap inside a frame that resynchronises (default 1000)\n"
               "  --position-mm N      car position at start (default 0)\n"
               "  --maker XX           drive maker code in I0 (default KW)\n"
               "  --no-init            travel without a prior I0 exchange\n"
               "  --frames N           exit after N master frames\n"
               "  --status S           print a status line every S seconds\n"
               "  --quiet              print only start, faults and the summary\n"
               "stdin commands: fault|warn|notready on|off, badsum|s7|late|noreply|garbage N,\n"
               "  rate badsum|s7|late|noreply|garbage P, clear, status, help\n");
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--device" && (v = next())) {
      o.device = v;
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
      o.gap = std::chrono::microseconds(std::strtol(v, nullptr, 10));
    } else if (a == "--position-mm" && (v = next())) {
      o.config.start_position_mm = std::strtoll(v, nullptr, 10);
    } else if (a == "--maker" && (v = next()) && std::strlen(v) == 2) {
      o.config.maker = {v[0], v[1]};
    } else if (a == "--no-init") {
      o.config.require_init = false;
    } else if (a == "--frames" && (v = next())) {
      o.max_frames = std::strtoull(v, nullptr, 10);
    } else if (a == "--status" && (v = next())) {
      o.status_interval_s = std::strtod(v, nullptr);
    } else if (a == "--quiet") {
      o.quiet = true;
    } else {
      return false;
    }
  }
  return !o.device.empty();
}

double secs(MonoTime t) {
  return std::chrono::duration<double>(t).count();
}

void print_event(const SimEvent& e, MonoTime start, bool quiet) {
  using K = SimEvent::Kind;
  const bool important = e.kind == K::Fault || e.kind == K::FaultCleared;
  if (quiet && !important) return;
  std::string what;
  switch (e.kind) {
    case K::PhaseChanged:
      what = std::string(liftd::sim::to_string(static_cast<liftd::sim::Phase>(e.value)));
      break;
    case K::TravelStarted:
      what = std::string(liftd::sim::to_string(static_cast<liftd::sim::TravelKind>(e.value))) +
             ", start distance " + std::to_string(e.detail) + " mm";
      break;
    case K::Fault:
    case K::FaultCleared:
      what = std::string(liftd::sim::to_string(static_cast<liftd::sim::FaultCause>(e.value)));
      break;
    case K::ChannelMessage:
      what = std::string("I") + static_cast<char>(e.value);
      break;
    default:
      what = std::to_string(e.value);
      break;
  }
  std::printf("[%10.3f] %s %s\n", secs(e.at - start),
              std::string(liftd::sim::to_string(e.kind)).c_str(), what.c_str());
}

void print_status(const DriveSim& sim) {
  const auto& c = sim.counters();
  std::printf(
      "status 0x%02X phase %s pos %.1f mm v %+.3f m/s frames %llu bad %llu repeats %llu "
      "travels %llu\n",
      sim.status_byte(), std::string(liftd::sim::to_string(sim.phase())).c_str(), sim.position_mm(),
      sim.velocity_mps(), static_cast<unsigned long long>(c.frames),
      static_cast<unsigned long long>(c.bad_frames), static_cast<unsigned long long>(c.repeats),
      static_cast<unsigned long long>(c.travels));
}

// Applies one stdin command; returns false for an unknown one.
bool command(DriveSim& sim, const std::string& line, MonoTime now) {
  std::istringstream in(line);
  std::string verb, arg;
  in >> verb >> arg;
  auto fault_named = [](const std::string& n, ReplyFault& f) {
    if (n == "badsum")
      f = ReplyFault::BadChecksum;
    else if (n == "s7")
      f = ReplyFault::MessageError;
    else if (n == "late")
      f = ReplyFault::Late;
    else if (n == "noreply")
      f = ReplyFault::NoReply;
    else if (n == "garbage")
      f = ReplyFault::Garbage;
    else
      return false;
    return true;
  };
  ReplyFault f{};
  if (verb == "fault")
    sim.set_general_fault(arg == "on", now);
  else if (verb == "warn")
    sim.set_advance_warning(arg == "on");
  else if (verb == "notready")
    sim.set_not_ready(arg == "on");
  else if (verb == "clear")
    sim.clear_reply_faults();
  else if (verb == "status")
    print_status(sim);
  else if (verb == "help")
    usage(stdout);
  else if (verb == "rate" && fault_named(arg, f)) {
    double p = 0.0;
    in >> p;
    sim.set_fault_rate(f, p);
  } else if (fault_named(verb, f)) {
    sim.inject(f, static_cast<std::uint32_t>(std::strtoul(arg.c_str(), nullptr, 10)));
  } else {
    return false;
  }
  return true;
}

void sleep_until(MonoTime t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t.count() / 1000000000);
  ts.tv_nsec = static_cast<long>(t.count() % 1000000000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop) {
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (!parse(argc, argv, opt)) {
    usage(stderr);
    return 2;
  }
  liftd::io::SerialSettings settings;  // DCP 7.1: 38400 8N1
  settings.rs485 = liftd::io::Rs485Mode::Auto;
  auto opened = liftd::io::SerialPort::open(opt.device, settings);
  if (!opened) {
    std::fprintf(stderr, "dcp-drive-sim: %s\n", opened.error().message().c_str());
    return 1;
  }
  liftd::io::SerialPort port = std::move(opened).value();
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  const MonoTime started = liftd::mono_now();
  DriveSim sim(opt.config, started);
  std::printf("dcp-drive-sim %s: DCP%c drive on %s, reply delay %lld us%s\n",
              std::string(liftd::kVersion).c_str(),
              opt.config.protocol == liftd::dcp::Protocol::Dcp3 ? '3' : '4', opt.device.c_str(),
              static_cast<long long>(opt.config.reply_delay.count()),
              port.features().rs485_enabled ? ", kernel RS485" : "");

  std::array<std::uint8_t, liftd::dcp::kFrameSize> frame{};
  std::size_t have = 0;
  MonoTime last_byte{};
  MonoTime next_status = liftd::mono_now();
  std::uint64_t resyncs = 0;
  bool stdin_open = true;
  std::string pending_line;

  while (!g_stop && (opt.max_frames == 0 || sim.counters().frames < opt.max_frames)) {
    // Wake for the gap deadline of a partial frame, else every 5 ms for the drive's timers.
    MonoTime now = liftd::mono_now();
    MonoTime wake = now + 5ms;
    if (have > 0) wake = std::min(wake, last_byte + opt.gap);
    pollfd fds[2] = {{port.fd(), POLLIN, 0}, {STDIN_FILENO, POLLIN, 0}};
    const auto wait_ms = std::chrono::ceil<std::chrono::milliseconds>(wake - now).count();
    const int n = poll(fds, stdin_open ? 2 : 1, static_cast<int>(std::max<long long>(0, wait_ms)));
    now = liftd::mono_now();
    if (n < 0 && errno != EINTR) break;
    if (have > 0 && now - last_byte > opt.gap) {
      have = 0;  // incomplete frame followed by silence: resynchronise
      ++resyncs;
    }
    if (n > 0 && (fds[0].revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
      std::array<std::uint8_t, 64> buf{};
      const auto r = port.read_available(buf);
      if (r.status == liftd::io::IoStatus::DeviceLost) {
        std::fprintf(stderr, "dcp-drive-sim: device lost\n");
        break;
      }
      for (std::size_t i = 0; i < r.bytes; ++i) {
        frame[have++] = buf[i];
        last_byte = now;
        if (have < frame.size()) continue;
        have = 0;
        const auto reply = sim.on_master_frame(frame, now);
        if (reply.size > 0) {
          sleep_until(now + reply.delay);
          (void)port.write_frame(reply.view());
        }
      }
    }
    if (stdin_open && n > 0 && (fds[1].revents & (POLLIN | POLLHUP)) != 0) {
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
          if (!line.empty() && !command(sim, line, now))
            std::printf("unknown command: %s\n", line.c_str());
        }
      }
    }
    sim.advance(liftd::mono_now());
    SimEvent e;
    while (sim.pop_event(e)) print_event(e, started, opt.quiet);
    if (opt.status_interval_s > 0 && now >= next_status) {
      print_status(sim);
      next_status = now + std::chrono::duration_cast<MonoTime>(
                              std::chrono::duration<double>(opt.status_interval_s));
    }
  }
  const auto& c = sim.counters();
  std::printf(
      "summary: frames %llu bad %llu replies %llu repeats %llu resyncs %llu travels %llu\n",
      static_cast<unsigned long long>(c.frames), static_cast<unsigned long long>(c.bad_frames),
      static_cast<unsigned long long>(c.replies), static_cast<unsigned long long>(c.repeats),
      static_cast<unsigned long long>(resyncs), static_cast<unsigned long long>(c.travels));
  return 0;
}
