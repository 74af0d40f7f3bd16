// uss-drive-sim: simulated USS slaves (lift drives, uss::sim::UssBusSim) on a serial device or a
// pty, 8E1 (USS B 3.2). Characters are read with their parity/framing marks (PARMRK) where the line
// gives them, each telegram is answered after the slave's reply delay, the car keeps moving
// between telegrams, and every rule of the spec the master breaks is printed. Faults are switched
// on stdin while it runs ("help" lists them); a summary is printed on exit.
//
// Line timing: on a real UART a read returns characters that arrived back to back, so they are
// stamped one character time apart ending at the read; on a pty (--pty, or a /dev/pts/ path) a
// telegram arrives at once and all its characters carry the read time. A pty cannot carry a
// parity error: the "parity" fault flips a bit of the reply's address byte there instead (the
// master then sees a BCC error); on a UART the reply is sent with odd parity.
#include <poll.h>
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common/mono_time.hpp"
#include "common/version.hpp"
#include "io/pty.hpp"
#include "io/serial_port.hpp"
#include "uss/line.hpp"
#include "uss/sim/uss_slave_sim.hpp"
#include "uss/timing.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::mono_now;
using liftd::MonoTime;
using liftd::uss::sim::UssBusSim;
using liftd::uss::sim::UssSlaveConfig;

volatile sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: uss-drive-sim (--device PATH | --pty) --address N [--address M ...] [options]\n"
      "  --device PATH          serial device or pty slave (8E1)\n"
      "  --pty                  create a pty pair and print the path for the master\n"
      "  --address N            a slave address 0..31 (repeat for several slaves)\n"
      "  --baud B               line speed (default 38400)\n"
      "  --pkw 0|3|4|127        PKW words PKW_ANZ (default 4; 127 = variable)\n"
      "  --pzd N                PZD words 0..16 (default 2)\n"
      "  --reply-delay-us N     reply delay (default 2000, at least the start pause)\n"
      "  --late-us N            the late-reply fault's delay (default 25000)\n"
      "  --telegram-timeout-ms N  C 3.1 telegram failure time (default 1000, 0 = off)\n"
      "  --nominal-mps V        car speed at 100 %% (default 1.0)\n"
      "  --accel V              ramp m/s^2 (default 0.5)\n"
      "  --start-mm N           car position at start (default 0)\n"
      "  --special echo|ignore  special telegrams (default echo)\n"
      "  --zero-based           array places count from 0\n"
      "  --status S             print the slaves every S seconds\n"
      "  --quiet                print only violations and the summary\n"
      "stdin commands ([A] = slave address, default the first):\n"
      "  silent|badbcc|badlge|parity|late|stale N [A]   fault the next N replies\n"
      "  fault on|off [A]   warning on|off [A]   local on|off [A]   authority on|off [A]\n"
      "  change PNU PLACE VALUE [A]   (a parameter changed elsewhere: spontaneous report)\n"
      "  clear [A], status, help, quit\n");
}

struct Options {
  std::string device;
  bool pty = false;
  std::vector<std::uint8_t> addresses;
  std::uint32_t baud = 38400;
  UssSlaveConfig slave;
  double status_s = 0;
  bool quiet = false;
};

std::optional<long> number(const char* text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 0);
  if (errno != 0 || end == text || *end != '\0') return std::nullopt;
  return v;
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "uss-drive-sim: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    const auto integer = [&](long min, long max) {
      const char* text = value();
      const auto v = number(text);
      if (!v || *v < min || *v > max) {
        std::fprintf(stderr, "uss-drive-sim: %s must be an integer %ld..%ld, not \"%s\"\n",
                     a.c_str(), min, max, text);
        std::exit(2);
      }
      return *v;
    };
    if (a == "--device") {
      o.device = value();
    } else if (a == "--pty") {
      o.pty = true;
    } else if (a == "--address") {
      o.addresses.push_back(static_cast<std::uint8_t>(integer(0, 31)));
    } else if (a == "--baud") {
      o.baud = static_cast<std::uint32_t>(integer(300, 4000000));
    } else if (a == "--pkw") {
      const long v = integer(0, 127);
      if (v != 0 && v != 3 && v != 4 && v != 127) {
        std::fprintf(stderr, "uss-drive-sim: --pkw is 0, 3, 4 or 127\n");
        std::exit(2);
      }
      o.slave.pkw = static_cast<liftd::uss::PkwLength>(v);
    } else if (a == "--pzd") {
      o.slave.pzd_words = static_cast<std::uint8_t>(integer(0, 16));
    } else if (a == "--reply-delay-us") {
      o.slave.reply_delay = std::chrono::microseconds(integer(0, 1000000));
    } else if (a == "--late-us") {
      o.slave.late_reply_delay = std::chrono::microseconds(integer(0, 10000000));
    } else if (a == "--telegram-timeout-ms") {
      o.slave.telegram_timeout = std::chrono::milliseconds(integer(0, 6500000));
    } else if (a == "--nominal-mps") {
      o.slave.car.nominal_mps = std::strtod(value(), nullptr);
    } else if (a == "--accel") {
      o.slave.car.accel_mps2 = std::strtod(value(), nullptr);
    } else if (a == "--start-mm") {
      o.slave.car.start_mm = static_cast<double>(integer(-1000000, 1000000));
      o.slave.car.bottom_mm = std::min(o.slave.car.bottom_mm, o.slave.car.start_mm - 200.0);
    } else if (a == "--special") {
      const std::string v = value();
      if (v == "echo") {
        o.slave.special = liftd::uss::sim::UssSpecialMode::Echo;
      } else if (v == "ignore") {
        o.slave.special = liftd::uss::sim::UssSpecialMode::Ignore;
      } else {
        return false;
      }
    } else if (a == "--zero-based") {
      o.slave.zero_based_index = true;
    } else if (a == "--status") {
      o.status_s = std::strtod(value(), nullptr);
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (a == "--version") {
      std::printf("uss-drive-sim %.*s\n", static_cast<int>(liftd::kVersion.size()),
                  liftd::kVersion.data());
      std::exit(0);
    } else if (a == "--help") {
      usage(stdout);
      std::exit(0);
    } else {
      std::fprintf(stderr, "uss-drive-sim: unknown option \"%s\"\n", a.c_str());
      return false;
    }
  }
  return (o.pty != !o.device.empty()) && !o.addresses.empty();
}

void print_slave(const liftd::uss::sim::UssSlaveSim& s) {
  const auto d = s.drive();
  const auto& st = s.stats();
  std::printf(
      "slave %u: %.*s STW %04X ZSW %04X HSW %d HIW %d car %.0f mm %.3f m/s; telegrams %llu "
      "replies %llu faulted %llu violations %llu unjudged %llu\n",
      s.address(), static_cast<int>(to_string(d.state).size()), to_string(d.state).data(), d.stw,
      d.zsw, d.hsw, d.hiw, d.position_mm, d.velocity_mps,
      static_cast<unsigned long long>(st.telegrams), static_cast<unsigned long long>(st.replies),
      static_cast<unsigned long long>(st.faulted_replies),
      static_cast<unsigned long long>(st.violations), static_cast<unsigned long long>(st.unjudged));
}

// One stdin line; false on "quit".
bool command(const std::string& line, UssBusSim& bus) {
  std::istringstream in(line);
  std::string verb;
  in >> verb;
  if (verb.empty()) return true;
  if (verb == "quit") return false;
  if (verb == "help") {
    usage(stdout);
    return true;
  }
  if (verb == "status") {
    for (const auto& s : bus.slaves()) print_slave(s);
    return true;
  }
  std::vector<std::string> args;
  for (std::string a; in >> a;) args.push_back(a);
  const auto slave_at = [&](std::size_t i) -> liftd::uss::sim::UssSlaveSim* {
    if (i >= args.size()) return &bus.slaves()[0];
    const auto a = number(args[i].c_str());
    return a && *a >= 0 && *a <= 31 ? bus.slave(static_cast<std::uint8_t>(*a)) : nullptr;
  };
  liftd::uss::sim::UssSlaveSim* s = nullptr;
  bool ok = true;
  if (const auto f = liftd::uss::sim::parse_uss_reply_fault(verb)) {
    const auto n = args.empty() ? std::optional<long>(1) : number(args[0].c_str());
    s = slave_at(1);
    ok = n && *n >= 0 && s != nullptr;
    if (ok) s->inject(*f, static_cast<std::uint32_t>(*n));
  } else if (verb == "fault" || verb == "warning" || verb == "local" || verb == "authority") {
    s = slave_at(1);
    ok = !args.empty() && (args[0] == "on" || args[0] == "off") && s != nullptr;
    const bool on = ok && args[0] == "on";
    if (ok && verb == "fault") s->set_drive_fault(on);
    if (ok && verb == "warning") s->set_warning(on);
    if (ok && verb == "local") s->set_local(on);
    if (ok && verb == "authority") s->set_pkw_authority(on);
  } else if (verb == "change") {
    s = slave_at(3);
    long pnu = -1, place = -1, value = -1;
    if (args.size() >= 3) {
      pnu = number(args[0].c_str()).value_or(-1);
      place = number(args[1].c_str()).value_or(-1);
      value = number(args[2].c_str()).value_or(-1);
    }
    ok = s != nullptr && pnu >= 0 && place >= 0 && place <= 255 && value >= 0 &&
         s->change_parameter(static_cast<std::uint16_t>(pnu), static_cast<std::uint8_t>(place),
                             static_cast<std::uint32_t>(value));
  } else if (verb == "clear") {
    s = slave_at(0);
    ok = s != nullptr;
    if (ok) {
      s->clear_faults();
      s->set_drive_fault(false);
      s->set_warning(false);
    }
  } else {
    std::printf("unknown command \"%s\"; try help\n", verb.c_str());
    std::fflush(stdout);
    return true;
  }
  std::printf("%s: %s\n", ok ? "ok" : "refused", line.c_str());
  std::fflush(stdout);
  return true;
}

// Sends one reply; on a UART an injected parity error goes out as odd parity for the reply.
void send_reply(liftd::io::SerialPort& port, const liftd::uss::sim::UssReply& r, bool pty_line,
                UssBusSim& bus) {
  std::array<std::uint8_t, liftd::uss::kMaxTelegramBytes> bytes{};
  std::copy_n(r.bytes.begin(), r.size, bytes.begin());
  const std::span<const std::uint8_t> view{bytes.data(), r.size};
  if (pty_line) {
    if (r.parity_error_at >= 0) bytes[static_cast<std::size_t>(r.parity_error_at)] ^= 0x01;
    bus.reply_sent(mono_now());  // before the write: the master cannot answer any earlier
    (void)port.write_frame(view);
    return;
  }
  termios saved{};
  const bool odd = r.parity_error_at >= 0 && tcgetattr(port.fd(), &saved) == 0;
  if (odd) {
    termios t = saved;
    t.c_cflag |= PARODD;
    (void)tcsetattr(port.fd(), TCSADRAIN, &t);
  }
  const MonoTime start = mono_now();
  (void)port.write_frame(view);
  bus.reply_sent(start + liftd::uss::transmission_time(bus.baud(), r.size));
  if (odd) (void)tcsetattr(port.fd(), TCSADRAIN, &saved);
}

}  // namespace

// Over 120 lines: the command line, the line and the read-and-reply loop, read top to bottom.
int main(int argc, char** argv) {
  Options opt;
  if (!parse(argc, argv, opt)) {
    usage(stderr);
    return 2;
  }
  std::vector<UssSlaveConfig> configs;
  for (const auto a : opt.addresses) {
    UssSlaveConfig c = opt.slave;
    c.address = a;
    configs.push_back(c);
  }
  std::optional<UssBusSim> bus;
  try {
    bus.emplace(configs, opt.baud, mono_now());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uss-drive-sim: %s\n", e.what());
    return 2;
  }

  liftd::io::SerialSettings settings;
  settings.baud = opt.baud;
  settings.parity = liftd::io::Parity::Even;  // USS B 3.2: 8 data bits, even parity, 1 stop
  settings.rs485 = liftd::io::Rs485Mode::Auto;
  liftd::io::SerialPort port;
  std::optional<liftd::io::PtyPair> pair;
  bool pty_line = opt.pty;
  bool marked = false;  // the stream carries PARMRK marks
  if (opt.pty) {
    auto p = liftd::io::PtyPair::create(settings);
    if (!p) {
      std::fprintf(stderr, "uss-drive-sim: %s\n", p.error().message().c_str());
      return 1;
    }
    pair.emplace(std::move(p.value()));
    port = pair->take_master();  // the master end: no line discipline, plain bytes
  } else {
    settings.mark_errors = true;
    auto p = liftd::io::SerialPort::open(opt.device, settings);
    if (!p) {
      std::fprintf(stderr, "uss-drive-sim: %s\n", p.error().message().c_str());
      return 1;
    }
    port = std::move(p.value());
    marked = true;
    pty_line = opt.device.rfind("/dev/pts/", 0) == 0;
  }

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  std::string list;
  for (const auto a : opt.addresses) list += (list.empty() ? "" : ",") + std::to_string(a);
  std::printf(
      "uss-drive-sim %.*s: slaves %s on %s, %u baud 8E1, PKW %u PZD %u, reply delay %lld us\n",
      static_cast<int>(liftd::kVersion.size()), liftd::kVersion.data(), list.c_str(),
      opt.pty ? "a pty" : opt.device.c_str(), opt.baud, static_cast<unsigned>(opt.slave.pkw),
      opt.slave.pzd_words,
      static_cast<long long>(std::chrono::duration_cast<std::chrono::microseconds>(
                                 std::max(opt.slave.reply_delay, liftd::uss::start_pause(opt.baud)))
                                 .count()));
  if (pair) std::printf("pty: %s\n", pair->slave_path().c_str());
  std::fflush(stdout);

  const auto tz = liftd::uss::character_time(opt.baud);
  liftd::uss::ParmrkDecoder decoder;
  std::array<std::uint8_t, 512> raw{};
  std::array<liftd::uss::RxChar, 512> chars{};
  std::array<liftd::uss::sim::UssViolation, 64> violations{};
  std::vector<liftd::uss::sim::UssDriveState> states;
  for (const auto& s : bus->slaves()) states.push_back(s.state());
  std::string pending;
  bool stdin_open = true;
  bool device_lost = false;
  MonoTime next_status = mono_now();
  while (g_stop == 0) {
    MonoTime now = mono_now();
    MonoTime wake = now + 5ms;
    if (const auto d = bus->deadline()) wake = std::min(wake, *d);
    if (const auto r = bus->next_reply_at()) wake = std::min(wake, *r);
    const auto wait_ms = std::max<long long>(
        0, std::chrono::duration_cast<std::chrono::milliseconds>(wake - now + 999us).count());
    pollfd fds[2] = {{port.fd(), POLLIN, 0}, {stdin_open ? STDIN_FILENO : -1, POLLIN, 0}};
    (void)::poll(fds, 2, static_cast<int>(wait_ms));
    now = mono_now();
    if ((fds[0].revents & POLLIN) != 0) {
      const auto r = port.read_available(raw);
      if (r.status == liftd::io::IoStatus::DeviceLost) {
        device_lost = true;
        break;
      }
      std::size_t n = r.bytes;
      if (marked) {
        n = decoder.decode({raw.data(), r.bytes}, chars);
      } else {
        for (std::size_t i = 0; i < n; ++i) chars[i] = {raw[i], liftd::uss::LineError::None};
      }
      for (std::size_t i = 0; i < n; ++i) {
        // A UART's characters came back to back and ended now; a pty's came at once.
        const MonoTime at = pty_line ? now : now - static_cast<long>(n - 1 - i) * tz;
        bus->on_char(chars[i], at);
      }
    } else if ((fds[0].revents & (POLLHUP | POLLERR)) != 0 && !opt.pty) {
      device_lost = true;
      break;
    }
    if ((fds[1].revents & (POLLIN | POLLHUP)) != 0) {
      char buf[256];
      const ssize_t got = ::read(STDIN_FILENO, buf, sizeof buf);
      if (got <= 0) {
        stdin_open = false;
      } else {
        pending.append(buf, static_cast<std::size_t>(got));
        for (auto nl = pending.find('\n'); nl != std::string::npos; nl = pending.find('\n')) {
          const std::string line = pending.substr(0, nl);
          pending.erase(0, nl + 1);
          if (!command(line, *bus)) g_stop = 1;
        }
      }
    }
    now = mono_now();
    bus->on_time(now);
    liftd::uss::sim::UssReply reply;
    while (bus->take_reply(now, reply)) send_reply(port, reply, pty_line, *bus);
    const std::size_t nv = bus->take_violations(violations);
    for (std::size_t i = 0; i < nv; ++i) {
      std::printf("VIOLATION slave %u: %.*s\n", violations[i].address,
                  static_cast<int>(violations[i].rule.size()), violations[i].rule.data());
    }
    if (!opt.quiet) {
      for (std::size_t i = 0; i < states.size(); ++i) {
        const auto& s = bus->slaves()[i];
        if (s.state() != states[i]) {
          states[i] = s.state();
          std::printf("slave %u: %.*s\n", s.address(),
                      static_cast<int>(to_string(s.state()).size()), to_string(s.state()).data());
        }
      }
    }
    if (opt.status_s > 0 && now >= next_status) {
      for (const auto& s : bus->slaves()) print_slave(s);
      next_status =
          now + std::chrono::duration_cast<MonoTime>(std::chrono::duration<double>(opt.status_s));
    }
  }
  if (device_lost) std::fprintf(stderr, "uss-drive-sim: device lost\n");
  for (const auto& s : bus->slaves()) {
    const auto& st = s.stats();
    const auto& rx = s.rx_counters();
    std::printf(
        "summary slave %u: telegrams %llu replies %llu mirrors %llu broadcasts %llu specials "
        "%llu pkw-requests %llu pkw-errors %llu spontaneous %llu/%llu eeprom %llu faulted %llu "
        "telegram-timeouts %llu violations %llu unjudged %llu rx-good %llu rx-rejected %llu "
        "error-word %04X\n",
        s.address(), static_cast<unsigned long long>(st.telegrams),
        static_cast<unsigned long long>(st.replies), static_cast<unsigned long long>(st.mirrors),
        static_cast<unsigned long long>(st.broadcasts),
        static_cast<unsigned long long>(st.specials),
        static_cast<unsigned long long>(st.pkw_requests),
        static_cast<unsigned long long>(st.pkw_errors),
        static_cast<unsigned long long>(st.spontaneous),
        static_cast<unsigned long long>(st.spontaneous_acknowledged),
        static_cast<unsigned long long>(st.eeprom_writes),
        static_cast<unsigned long long>(st.faulted_replies),
        static_cast<unsigned long long>(st.telegram_timeouts),
        static_cast<unsigned long long>(st.violations),
        static_cast<unsigned long long>(st.unjudged), static_cast<unsigned long long>(rx.good),
        static_cast<unsigned long long>(rx.rejected), rx.error_word);
  }
  return device_lost ? 1 : 0;
}
