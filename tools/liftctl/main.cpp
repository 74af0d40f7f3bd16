// liftctl: command-line client of the liftd JSON API (see docs/api.md).
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <deque>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "format.hpp"

namespace {

using nlohmann::json;

/// Exit codes: documented in usage().
constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;  // the daemon answered with an error
constexpr int kExitUsage = 2;
constexpr int kExitNoDaemon = 3;  // cannot connect, or the connection broke
/// How long to wait for a reply before giving up.
constexpr int kReplyTimeoutMs = 10'000;

void usage(std::FILE* out) {
  std::fputs(
      "usage: liftctl [--socket PATH] [--json] COMMAND [ARGS]\n"
      "\n"
      "commands:\n"
      "  status                 link, drive, car, travel, faults\n"
      "  watch                  live view of state changes and events (Ctrl-C ends)\n"
      "  stats                  link counters, cycle timing, API counters\n"
      "  trace [COUNT]          newest DCP frames (default 100)\n"
      "  display                the drive's remote display\n"
      "  key N                  press keypad button N (1..5) on the drive\n"
      "  reset                  ask the drive for a fault reset\n"
      "  power mains|emergency [SAVING]   set the power supply mode (SAVING 0..2)\n"
      "  load PERCENT           car load for the next travel\n"
      "  travel FLOOR [SPEED]   travel to a floor (extends a running DCP4 travel)\n"
      "  stop                   controlled stop; clears the calls queue\n"
      "  fast-stop              DCP fast stop of the running travel\n"
      "  relevel                relevel to the nearest floor\n"
      "  calls [add|cancel N]   list, add or cancel destinations (served in order)\n"
      "  inspection on|off [up|down|none]   software inspection; repeat to hold a direction\n"
      "  fast-start arm FLOOR|go|abort      DCP fast start while the doors close\n"
      "  uss-read PNU [array|description|text INDEX] [@ADDRESS]\n"
      "                         read a parameter of the USS drive (or of slave ADDRESS)\n"
      "  uss-write PNU VALUE [dword] [eeprom] [array INDEX] [@ADDRESS]\n"
      "                         change a parameter of the USS drive (or of slave ADDRESS)\n"
      "  uss-mirror [ADDRESS]   mirror telegram to the USS drive (or slave ADDRESS)\n"
      "  config                 the daemon's effective configuration\n"
      "  version                daemon and API version\n"
      "  raw 'JSON'             send any request, e.g. raw '{\"cmd\":\"status\"}'\n"
      "\n"
      "options:\n"
      "  --socket PATH   API socket (default: $LIFTD_SOCKET, else /run/liftd/api.sock)\n"
      "  --json          print the raw JSON result instead of a summary\n"
      "\n"
      "exit status: 0 ok, 1 the daemon refused the request, 2 usage error,\n"
      "             3 cannot reach the daemon\n",
      out);
}

/// A blocking connection to the daemon.
class Connection {
 public:
  ~Connection() {
    if (fd_ >= 0) ::close(fd_);
  }

  /// Connects; on failure prints why and returns false.
  bool open(const std::string& path) {
    if (path.size() >= sizeof(sockaddr_un{}.sun_path)) {
      std::fprintf(stderr, "liftctl: socket path too long: %s\n", path.c_str());
      return false;
    }
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) {
      std::fprintf(stderr, "liftctl: socket(): %s\n", std::strerror(errno));
      return false;
    }
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) return true;
    const int error = errno;
    switch (error) {
      case ENOENT:
        std::fprintf(stderr,
                     "liftctl: %s does not exist: liftd is not running, or uses another socket "
                     "(--socket or LIFTD_SOCKET)\n",
                     path.c_str());
        break;
      case ECONNREFUSED:
        std::fprintf(stderr, "liftctl: nothing listens on %s: liftd is not running\n",
                     path.c_str());
        break;
      case EACCES:
      case EPERM:
        std::fprintf(stderr,
                     "liftctl: permission denied on %s: your user must be in one of liftd's "
                     "groups: liftd (read), liftd-control (control), liftd-io (inputs); see "
                     "docs/operations.md, Users and groups\n",
                     path.c_str());
        break;
      default:
        std::fprintf(stderr, "liftctl: cannot connect to %s: %s\n", path.c_str(),
                     std::strerror(error));
    }
    return false;
  }

  bool send_line(const std::string& line) {
    std::string data = line + "\n";
    std::size_t done = 0;
    while (done < data.size()) {
      const ssize_t n = ::send(fd_, data.data() + done, data.size() - done, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

  /// Next line; nullopt on EOF, error or timeout (-1 waits forever).
  std::optional<std::string> read_line(int timeout_ms) {
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      pollfd p{fd_, POLLIN, 0};
      const int rc = ::poll(&p, 1, timeout_ms);
      if (rc < 0 && errno == EINTR) continue;
      if (rc <= 0) {
        if (rc == 0)
          std::fprintf(stderr, "liftctl: no answer from liftd within %d ms\n", timeout_ms);
        return std::nullopt;
      }
      char chunk[8192];
      const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return std::nullopt;
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  /// Next line parsed as JSON; nullopt on EOF or garbage (reported).
  std::optional<json> read_json(int timeout_ms) {
    const auto line = read_line(timeout_ms);
    if (!line) return std::nullopt;
    json message = json::parse(*line, nullptr, false);
    if (message.is_discarded()) {
      std::fprintf(stderr, "liftctl: liftd sent something that is not JSON: %s\n", line->c_str());
      return std::nullopt;
    }
    return message;
  }

 private:
  int fd_ = -1;
  std::string buffer_;
};

/// Prints an error reply; returns the exit status.
int report_error(const json& reply) {
  const json error = reply.value("error", json::object());
  const std::string code = error.value("code", "unknown");
  const std::string message = error.value("message", "");
  std::fprintf(stderr, "liftctl: %s: %s\n", code.c_str(), message.c_str());
  if (code == "forbidden") {
    std::fprintf(stderr, "liftctl: ask for membership of the liftd control group (docs/api.md)\n");
  }
  return kExitFailed;
}

/// Sends `request` (id 1) and returns its reply, skipping events; nullopt if the daemon went away.
std::optional<json> call(Connection& conn, json request) {
  request["id"] = 1;
  if (!conn.send_line(request.dump())) {
    std::fprintf(stderr, "liftctl: liftd closed the connection\n");
    return std::nullopt;
  }
  for (;;) {
    auto message = conn.read_json(kReplyTimeoutMs);
    if (!message) {
      std::fprintf(stderr, "liftctl: liftd closed the connection without answering\n");
      return std::nullopt;
    }
    if (message->contains("ok")) return message;
  }
}

std::string clock_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[16];
  std::strftime(buf, sizeof buf, "%H:%M:%S", &tm);
  return buf;
}

int run_watch(Connection& conn, bool raw_json) {
  const auto reply = call(conn, {{"cmd", "watch"}, {"enable", true}});
  if (!reply) return kExitNoDaemon;
  if (reply->value("ok", false) != true) return report_error(*reply);
  const bool tty = ::isatty(STDOUT_FILENO) == 1 && !raw_json;
  json last_state = nullptr;
  std::deque<std::string> recent;  // the newest non-state events, for the terminal view
  constexpr std::size_t kRecentEvents = 12;
  for (;;) {
    const auto line = conn.read_line(-1);
    if (!line) {
      std::fprintf(stderr, "liftctl: liftd closed the connection\n");
      return kExitNoDaemon;
    }
    if (raw_json) {
      std::printf("%s\n", line->c_str());
      std::fflush(stdout);
      continue;
    }
    const json message = json::parse(*line, nullptr, false);
    if (message.is_discarded() || !message.contains("event")) continue;
    const std::string name = message.value("event", "");
    const json data = message.value("data", json(nullptr));
    if (!tty) {
      std::printf("%s %s\n", clock_now().c_str(), liftctl::format_event_line(name, data).c_str());
      std::fflush(stdout);
      continue;
    }
    if (name == "state") {
      last_state = data;
    } else {
      recent.push_back(clock_now() + " " + liftctl::format_event_line(name, data));
      if (recent.size() > kRecentEvents) recent.pop_front();
    }
    // Home the cursor and clear the screen, then redraw.
    std::string screen = "\x1b[H\x1b[2J";
    screen += "liftd watch  " + clock_now() + "  (Ctrl-C to quit)\n\n";
    screen += last_state.is_null() ? "(no state yet)\n" : liftctl::format_status(last_state);
    screen += "\nrecent events:\n";
    for (const auto& e : recent) screen += "  " + e + "\n";
    std::fputs(screen.c_str(), stdout);
    std::fflush(stdout);
  }
}

std::optional<long> parse_int(const std::string& s) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno != 0) return std::nullopt;
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  std::string socket_path;
  if (const char* env = std::getenv("LIFTD_SOCKET"); env != nullptr && *env != '\0') {
    socket_path = env;
  } else {
    socket_path = "/run/liftd/api.sock";
  }
  bool raw_json = false;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--socket" || arg.rfind("--socket=", 0) == 0) {
      const bool inline_value = arg != "--socket";
      if (!inline_value && i + 1 >= argc) {
        std::fprintf(stderr,
                     "liftctl: --socket needs a PATH (the API socket, e.g. "
                     "/run/liftd/api.sock)\n");
        return kExitUsage;
      }
      socket_path = inline_value ? arg.substr(9) : argv[++i];
      if (socket_path.empty()) {
        std::fprintf(stderr, "liftctl: --socket needs a PATH, got an empty one\n");
        return kExitUsage;
      }
    } else if (arg == "--json") {
      raw_json = true;
    } else if (arg == "-h" || arg == "--help") {
      usage(stdout);
      return kExitOk;
    } else if (arg.size() > 1 && arg[0] == '-' && args.empty()) {
      std::fprintf(stderr, "liftctl: unknown option %s\n", arg.c_str());
      usage(stderr);
      return kExitUsage;
    } else {
      args.push_back(arg);
    }
  }
  if (args.empty()) {
    usage(stderr);
    return kExitUsage;
  }
  const std::string command = args[0];
  const auto bad_usage = [](const char* message) {
    std::fprintf(stderr, "liftctl: %s\n", message);
    return kExitUsage;
  };

  json request;
  if (command == "status" || command == "stats" || command == "display" || command == "config" ||
      command == "version") {
    if (args.size() != 1) return bad_usage("this command takes no arguments");
    request = {{"cmd", command}};
  } else if (command == "watch") {
    if (args.size() != 1) return bad_usage("watch takes no arguments");
  } else if (command == "trace") {
    request = {{"cmd", "trace"}};
    if (args.size() == 2) {
      const auto count = parse_int(args[1]);
      if (!count) return bad_usage("trace COUNT: COUNT must be a number");
      request["count"] = *count;
    } else if (args.size() > 2) {
      return bad_usage("usage: trace [COUNT]");
    }
  } else if (command == "key") {
    const auto key = args.size() == 2 ? parse_int(args[1]) : std::nullopt;
    if (!key) return bad_usage("usage: key N (N = 1..5)");
    request = {{"cmd", "key"}, {"key", *key}};
  } else if (command == "reset") {
    if (args.size() != 1) return bad_usage("reset takes no arguments");
    request = {{"cmd", "drive_reset"}};
  } else if (command == "power") {
    if (args.size() < 2 || args.size() > 3)
      return bad_usage("usage: power mains|emergency [SAVING]");
    request = {{"cmd", "power"}, {"supply", args[1]}};
    if (args.size() == 3) {
      const auto saving = parse_int(args[2]);
      if (!saving) return bad_usage("power: SAVING must be 0, 1 or 2");
      request["saving"] = *saving;
    }
  } else if (command == "load") {
    const auto percent = args.size() == 2 ? parse_int(args[1]) : std::nullopt;
    if (!percent) return bad_usage("usage: load PERCENT");
    request = {{"cmd", "load"}, {"percent", *percent}};
  } else if (command == "travel") {
    const auto floor = args.size() >= 2 ? parse_int(args[1]) : std::nullopt;
    if (!floor || args.size() > 3) return bad_usage("usage: travel FLOOR [V4|V3|...]");
    request = {{"cmd", "travel"}, {"floor", *floor}};
    if (args.size() == 3) request["speed"] = args[2];
  } else if (command == "stop" || command == "fast-stop" || command == "relevel") {
    if (args.size() != 1) return bad_usage("this command takes no arguments");
    request = {{"cmd", command == "fast-stop" ? "fast_stop" : command}};
  } else if (command == "calls") {
    request = {{"cmd", "calls"}};
    if (args.size() == 3) {
      const auto floor = parse_int(args[2]);
      if (!floor || (args[1] != "add" && args[1] != "cancel")) {
        return bad_usage("usage: calls [add|cancel FLOOR]");
      }
      request["action"] = args[1];
      request["floor"] = *floor;
    } else if (args.size() != 1) {
      return bad_usage("usage: calls [add|cancel FLOOR]");
    }
  } else if (command == "inspection") {
    if (args.size() < 2 || args.size() > 3) return bad_usage("usage: inspection on|off [up|down]");
    request = {{"cmd", "inspection"}, {"mode", args[1]}};
    if (args.size() == 3) request["direction"] = args[2];
  } else if (command == "fast-start") {
    if (args.size() < 2) return bad_usage("usage: fast-start arm FLOOR|go|abort");
    request = {{"cmd", "fast_start"}, {"action", args[1]}};
    if (args[1] == "arm") {
      const auto floor = args.size() == 3 ? parse_int(args[2]) : std::nullopt;
      if (!floor) return bad_usage("usage: fast-start arm FLOOR");
      request["floor"] = *floor;
    } else if (args.size() != 2) {
      return bad_usage("usage: fast-start arm FLOOR|go|abort");
    }
  } else if (command == "uss-read" || command == "uss-write") {
    const bool write = command == "uss-write";
    const char* use = write ? "usage: uss-write PNU VALUE [dword] [eeprom] [array INDEX] [@ADDRESS]"
                            : "usage: uss-read PNU [array|description|text INDEX] [@ADDRESS]";
    const std::size_t first_option = write ? 3 : 2;
    const auto pnu = args.size() >= first_option ? parse_int(args[1]) : std::nullopt;
    if (!pnu) return bad_usage(use);
    request = {{"cmd", write ? "uss_write" : "uss_read"}, {"pnu", *pnu}};
    if (write) {
      const auto value = parse_int(args[2]);
      if (!value) return bad_usage(use);
      request["value"] = *value;
    }
    for (std::size_t i = first_option; i < args.size(); ++i) {
      const std::string& word = args[i];
      if (write && (word == "dword" || word == "eeprom")) {
        if (word == "dword") request["width"] = "dword";
        if (word == "eeprom") request["eeprom"] = true;
      } else if (word == "array" || (!write && (word == "description" || word == "text"))) {
        const auto index = i + 1 < args.size() ? parse_int(args[i + 1]) : std::nullopt;
        if (!index) return bad_usage(use);
        request["target"] = word;
        request["index"] = *index;
        ++i;
      } else if (word.size() > 1 && word[0] == '@' && parse_int(word.substr(1))) {
        request["address"] = *parse_int(word.substr(1));
      } else {
        return bad_usage(use);
      }
    }
  } else if (command == "uss-mirror") {
    request = {{"cmd", "uss_mirror"}};
    if (args.size() > 2) return bad_usage("usage: uss-mirror [ADDRESS]");
    if (args.size() == 2) {
      const auto address = parse_int(args[1]);
      if (!address) return bad_usage("usage: uss-mirror [ADDRESS]");
      request["address"] = *address;
    }
  } else if (command == "raw") {
    if (args.size() != 2) return bad_usage("usage: raw '{\"cmd\":...}'");
    request = json::parse(args[1], nullptr, false);
    if (request.is_discarded() || !request.is_object()) {
      return bad_usage("raw: the argument must be one JSON object");
    }
  } else {
    std::fprintf(stderr, "liftctl: unknown command \"%s\"\n", command.c_str());
    usage(stderr);
    return kExitUsage;
  }

  Connection conn;
  if (!conn.open(socket_path)) return kExitNoDaemon;
  const auto hello = conn.read_json(kReplyTimeoutMs);
  if (!hello || hello->value("event", "") != "hello") {
    if (hello && hello->contains("error")) {
      report_error(*hello);  // e.g. busy: too many clients
      return kExitNoDaemon;
    }
    std::fprintf(stderr, "liftctl: %s did not greet like liftd\n", socket_path.c_str());
    return kExitNoDaemon;
  }
  if (command == "watch") return run_watch(conn, raw_json);

  if (command == "raw") {
    // The caller's id (if any) is kept; the reply is printed as received.
    if (!conn.send_line(request.dump())) return kExitNoDaemon;
    for (;;) {
      const auto message = conn.read_json(kReplyTimeoutMs);
      if (!message) return kExitNoDaemon;
      if (!message->contains("ok")) continue;
      std::printf("%s\n", message->dump().c_str());
      return message->value("ok", false) ? kExitOk : kExitFailed;
    }
  }

  const auto reply = call(conn, request);
  if (!reply) return kExitNoDaemon;
  if (reply->value("ok", false) != true) return report_error(*reply);
  const json result = reply->value("result", json::object());
  if (raw_json) {
    std::printf("%s\n", result.dump(2).c_str());
    return kExitOk;
  }
  std::string out;
  if (command == "status") {
    out = liftctl::format_status(result);
  } else if (command == "stats") {
    out = liftctl::format_stats(result);
  } else if (command == "trace") {
    out = liftctl::format_trace(result);
  } else if (command == "display") {
    out = liftctl::format_display(result);
  } else if (command == "config") {
    out = result.value("config", json::object()).dump(2) + "\n";
  } else if (command == "travel" || command == "stop" || command == "fast-stop" ||
             command == "relevel" || command == "inspection" || command == "fast-start" ||
             command == "calls") {
    out = liftctl::format_travel_result(request, result);
  } else {
    out = liftctl::format_generic(result);
  }
  std::fputs(out.c_str(), stdout);
  return kExitOk;
}
