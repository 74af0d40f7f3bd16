// sch001-sim: the simulated SCH001 card and hydraulic car as a process of its own, for a liftd
// (or any controller) that speaks to it over CAN: on a Unix SOCK_SEQPACKET socket carrying
// struct can_frame (--socket PATH: liftd's can.interface "unix:PATH") or on a SocketCAN
// interface (--interface can0). It sends the card's status frame every 100 ms, moves the car by
// what the controller answers, and prints every rule of the card document the controller breaks.
// Faults are switched on stdin while it runs ("help" lists them).
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <string>

#include "can/socket.hpp"
#include "common/mono_time.hpp"
#include "common/version.hpp"
#include "sch001/sim/sch001_card_sim.hpp"

namespace {

using liftd::mono_now;
using liftd::MonoTime;

volatile sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: sch001-sim (--socket PATH | --interface IFACE) [options]\n"
               "  --socket PATH        listen on a Unix SOCK_SEQPACKET socket carrying struct\n"
               "                       can_frame (liftd: can.interface \"unix:PATH\")\n"
               "  --interface IFACE    use a SocketCAN interface (125 kbit/s, set by the system)\n"
               "  --base N             card parameter P479 (0 = 0x550; default 0)\n"
               "  --node N             card parameter P480 (default 49: controller at base + 49)\n"
               "  --start-mm MM        where the car stands at power-on (default 0)\n"
               "  --fast-down-sp3      fast down by SP3 (card P453 = 1) instead of HSP\n"
               "  --status-interval S  print the car and the card every S seconds (default 0)\n"
               "  --version, --help\n"
               "stdin commands: err on|off, rdy on|off, t1 on|off, p1 on|off, p2 on|off,\n"
               "  silence on|off, cold on|off, sink on|off, timeout on|off (send 0x52/0x5A),\n"
               "  busoff (unix socket only), status, quit\n");
}

std::optional<long> number(const char* text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 0);
  if (errno != 0 || end == text || *end != '\0') return std::nullopt;
  return v;
}

void print_status(const liftd::sch001::sim::Sch001CardSim& card) {
  const auto& s = card.state();
  std::printf(
      "car %.0f mm %.2f m/s; card ERR=%d RDY=%d T1=%d P1=%d P2=%d%s; commands 0x%02X, "
      "floor %u -> %u; %llu status frames, %llu answers, %llu violations\n",
      s.position_mm, s.velocity_mps, s.status.err, s.status.rdy, s.status.t1, s.status.p1,
      s.status.p2, s.silent ? " SILENT" : "", s.commands.to_byte(), s.current_floor,
      s.destination_floor, static_cast<unsigned long long>(s.status_frames),
      static_cast<unsigned long long>(s.answers), static_cast<unsigned long long>(s.violations));
  std::fflush(stdout);
}

/// One stdin line; false on "quit".
bool command(const std::string& line, liftd::sch001::sim::Sch001CardSim& card,
             liftd::can::CanSocket* peer, bool unix_socket) {
  std::istringstream in(line);
  std::string word, arg;
  in >> word >> arg;
  const bool on = arg != "off";
  if (word.empty()) return true;
  if (word == "quit") return false;
  if (word == "help") {
    usage(stdout);
  } else if (word == "err") {
    card.set_err(on);
  } else if (word == "rdy") {
    card.set_rdy(on);
  } else if (word == "t1") {
    card.set_t1(on);
  } else if (word == "p1") {
    card.set_p1(on);
  } else if (word == "p2") {
    card.set_p2(on);
  } else if (word == "silence") {
    card.set_silent(on);
  } else if (word == "cold") {
    card.set_cold_oil(on);
  } else if (word == "sink") {
    card.set_sink(on ? 2.0 : 0.0);
  } else if (word == "timeout") {
    card.send_timeout_command(on);
  } else if (word == "busoff") {
    if (!unix_socket || peer == nullptr) {
      std::printf("busoff: only on a Unix socket with a controller connected\n");
    } else {
      liftd::can::ErrorReport report;
      report.bus_off = true;
      (void)peer->write_error(report);
    }
  } else if (word == "status") {
    print_status(card);
    return true;
  } else {
    std::printf("unknown command \"%s\"; try help\n", word.c_str());
    return true;
  }
  std::printf("ok: %s\n", line.c_str());
  std::fflush(stdout);
  return true;
}

}  // namespace

// Over 120 lines: the command line, the endpoint and the poll loop, read top to bottom.
int main(int argc, char** argv) {
  std::string socket_path, interface;
  long base = 0, node = 49, start_mm = 0;
  double status_interval = 0;
  bool sp3 = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "sch001-sim: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    const auto integer = [&](long min, long max) {
      const char* text = value();
      const auto v = number(text);
      if (!v || *v < min || *v > max) {
        std::fprintf(stderr, "sch001-sim: %s must be an integer %ld..%ld, not \"%s\"\n", a.c_str(),
                     min, max, text);
        std::exit(2);
      }
      return *v;
    };
    if (a == "--socket") {
      socket_path = value();
    } else if (a == "--interface") {
      interface = value();
    } else if (a == "--base") {
      base = integer(0, 0x7A0);
    } else if (a == "--node") {
      node = integer(2, 95);
    } else if (a == "--start-mm") {
      start_mm = integer(-999999, 999999);
    } else if (a == "--fast-down-sp3") {
      sp3 = true;
    } else if (a == "--status-interval") {
      status_interval = static_cast<double>(integer(0, 3600));
    } else if (a == "--version") {
      std::printf("sch001-sim %.*s\n", static_cast<int>(liftd::kVersion.size()),
                  liftd::kVersion.data());
      return 0;
    } else if (a == "--help") {
      usage(stdout);
      return 0;
    } else {
      std::fprintf(stderr, "sch001-sim: unknown option \"%s\"\n", a.c_str());
      usage(stderr);
      return 2;
    }
  }
  if (socket_path.empty() == interface.empty()) {
    std::fprintf(stderr, "sch001-sim: give exactly one of --socket PATH and --interface IFACE\n");
    return 2;
  }
  liftd::sch001::sim::CardSimConfig config;
  config.ids =
      *liftd::sch001::ids_for(static_cast<std::uint32_t>(base), static_cast<std::uint32_t>(node));
  config.fast_down_sp3 = sp3;
  config.start_mm = static_cast<double>(start_mm);
  config.bottom_mm = config.start_mm - 200.0;
  liftd::sch001::sim::Sch001CardSim card(config, mono_now());

  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  signal(SIGPIPE, SIG_IGN);

  int listener = -1;
  std::optional<liftd::can::CanSocket> peer;
  if (!socket_path.empty()) {
    auto l = liftd::can::listen_unix(socket_path);
    if (!l) {
      std::fprintf(stderr, "sch001-sim: %s: %s\n", l.error().what.c_str(),
                   std::strerror(l.error().code));
      return 1;
    }
    listener = l.value();
    std::printf("sch001-sim: listening on %s (card ids 0x%03X in, 0x%03X out)\n",
                socket_path.c_str(), config.ids.to_card, config.ids.from_card);
  } else {
    auto s = liftd::can::CanSocket::open(interface, {config.ids.to_card});
    if (!s) {
      std::fprintf(stderr, "sch001-sim: %s: %s\n", s.error().what.c_str(),
                   std::strerror(s.error().code));
      return 1;
    }
    peer.emplace(std::move(s.value()));
    std::printf("sch001-sim: on %s (card ids 0x%03X in, 0x%03X out)\n", interface.c_str(),
                config.ids.to_card, config.ids.from_card);
  }
  std::fflush(stdout);
  MonoTime last_status = mono_now();
  // A failed interface is tried again this often (what liftd survives, the card survives too).
  constexpr auto kReopenPeriod = std::chrono::milliseconds(200);
  MonoTime reopen_at{};
  std::string pending_line;
  while (g_stop == 0) {
    pollfd fds[3] = {
        {STDIN_FILENO, POLLIN, 0}, {listener, POLLIN, 0}, {peer ? peer->fd() : -1, POLLIN, 0}};
    (void)::poll(fds, 3, 5);
    const MonoTime now = mono_now();
    if ((fds[0].revents & POLLIN) != 0) {
      char buf[256];
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n > 0) {
        pending_line.append(buf, static_cast<std::size_t>(n));
        for (auto nl = pending_line.find('\n'); nl != std::string::npos;
             nl = pending_line.find('\n')) {
          const std::string line = pending_line.substr(0, nl);
          pending_line.erase(0, nl + 1);
          if (!command(line, card, peer ? &*peer : nullptr, listener >= 0)) g_stop = 1;
        }
      }
    }
    if (listener >= 0 && (fds[1].revents & POLLIN) != 0) {
      const int fd = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd >= 0) {
        peer.emplace(liftd::can::CanSocket::adopt(fd, {config.ids.to_card}));
        std::printf("sch001-sim: controller connected\n");
        std::fflush(stdout);
      }
    }
    while (peer) {
      const liftd::can::Received r = peer->read();
      if (r.kind == liftd::can::Received::Kind::Frame) {
        card.on_frame(r.frame, now);
        continue;
      }
      if (r.kind == liftd::can::Received::Kind::Closed ||
          r.kind == liftd::can::Received::Kind::Failed) {
        if (listener >= 0) {
          std::printf("sch001-sim: controller gone\n");
        } else {  // the interface went down or away: a card on the bus waits for it
          std::printf("sch001-sim: %s failed (%s); reopening\n", interface.c_str(),
                      std::strerror(r.errno_value));
          reopen_at = now + kReopenPeriod;
        }
        std::fflush(stdout);
        peer.reset();
      }
      break;
    }
    if (!peer && listener < 0 && now >= reopen_at) {
      auto s = liftd::can::CanSocket::open(interface, {config.ids.to_card});
      if (s) {
        peer.emplace(std::move(s.value()));
        std::printf("sch001-sim: %s open again\n", interface.c_str());
        std::fflush(stdout);
      } else {
        reopen_at = now + kReopenPeriod;
      }
    }
    if (peer) {  // the card talks only when a controller is there to answer
      if (const auto frame = card.poll(now)) (void)peer->write(*frame);
    }
    for (const auto& v : card.take_violations()) {
      std::printf("VIOLATION: %s\n", v.rule.c_str());
      std::fflush(stdout);
    }
    if (status_interval > 0 &&
        now - last_status >= std::chrono::duration<double>(status_interval)) {
      print_status(card);
      last_status = now;
    }
  }
  print_status(card);
  if (listener >= 0) {
    ::close(listener);
    ::unlink(socket_path.c_str());
  }
  return 0;
}
