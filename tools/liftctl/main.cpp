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
#include "learn_apply.hpp"
#include "plot.hpp"
#include "record_view.hpp"

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
      "  plot [--last N] [--svg FILE]\n"
      "                         the last N travels' curves (default 5): a chart, or an SVG file\n"
      "  counters [reset NAME...]\n"
      "                         the lift's lifetime counters and stopping errors (kept across\n"
      "                         restarts); reset sets the named ones to zero (control access)\n"
      "  history [--from T] [--to T] [--floor N] [--outcome arrived|aborted] [--cause C]\n"
      "          [--limit N]    the travels of the lift's record, newest first (T: UTC,\n"
      "                         2026-11-01 or 2026-11-01T08:00:00Z)\n"
      "  plot --trend [--from T] [--to T] [--floor N] [--svg FILE]\n"
      "                         stopping error and floor-to-floor time per floor and day\n"
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
      "  calls insert N [POS]   put floor N at queue position POS (0: first; default: last)\n"
      "  calls set [N...]       replace the queue (a floor may repeat, not twice in a row)\n"
      "  learn [--apply FILE]   learning travel: each floor's level from the shaft's level\n"
      "                         zones; --apply writes them into the configuration FILE\n"
      "                         (the old one kept as FILE.bak); floors take effect at restart\n"
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

/// What the command line selects: the socket, the output form and the subcommand with its words.
struct Options {
  std::string socket_path;
  bool raw_json = false;
  std::vector<std::string> args;  ///< args[0] is the subcommand
};

/// Reads the options into `options`; an exit status when liftctl ends here (help, usage error).
std::optional<int> parse_options(int argc, char** argv, Options& options) {
  if (const char* env = std::getenv("LIFTD_SOCKET"); env != nullptr && *env != '\0') {
    options.socket_path = env;
  } else {
    options.socket_path = "/run/liftd/api.sock";
  }
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
      options.socket_path = inline_value ? arg.substr(9) : argv[++i];
      if (options.socket_path.empty()) {
        std::fprintf(stderr, "liftctl: --socket needs a PATH, got an empty one\n");
        return kExitUsage;
      }
    } else if (arg == "--json") {
      options.raw_json = true;
    } else if (arg == "-h" || arg == "--help") {
      usage(stdout);
      return kExitOk;
    } else if (arg.size() > 1 && arg[0] == '-' && options.args.empty()) {
      std::fprintf(stderr, "liftctl: unknown option %s\n", arg.c_str());
      usage(stderr);
      return kExitUsage;
    } else {
      options.args.push_back(arg);
    }
  }
  if (options.args.empty()) {
    usage(stderr);
    return kExitUsage;
  }
  return std::nullopt;
}

using Args = std::vector<std::string>;
/// A subcommand's request built from its words; nullopt after a usage error was printed.
using Request = std::optional<json>;

Request bad_usage(const char* message) {
  std::fprintf(stderr, "liftctl: %s\n", message);
  return std::nullopt;
}

/// status, stats, display, config, version: the request is the command alone.
Request request_plain(const Args& args) {
  if (args.size() != 1) return bad_usage("this command takes no arguments");
  return json{{"cmd", args[0]}};
}

/// watch sends its own request once connected (run_watch).
Request request_watch(const Args& args) {
  if (args.size() != 1) return bad_usage("watch takes no arguments");
  return json{};
}

Request request_trace(const Args& args) {
  json request = {{"cmd", "trace"}};
  if (args.size() == 2) {
    const auto count = parse_int(args[1]);
    if (!count) return bad_usage("trace COUNT: COUNT must be a number");
    request["count"] = *count;
  } else if (args.size() > 2) {
    return bad_usage("usage: trace [COUNT]");
  }
  return request;
}

/// plot asks for `travels` (with --trend: `trend`); run_plot prints or writes what comes back.
Request request_plot(const Args& args) {
  std::string error;
  if (liftctl::wants_trend(args)) {
    const auto trend = liftctl::trend_request(args, error);
    if (!trend) return bad_usage(error.c_str());
    return trend->request;
  }
  const auto options = liftctl::parse_plot_args(args, error);
  if (!options) return bad_usage(error.c_str());
  return json{{"cmd", "travels"}, {"last", options->last}};
}

Request request_counters(const Args& args) {
  std::string error;
  auto request = liftctl::counters_request(args, error);
  if (!request) return bad_usage(error.c_str());
  return request;
}

Request request_history(const Args& args) {
  std::string error;
  auto request = liftctl::history_request(args, error);
  if (!request) return bad_usage(error.c_str());
  return request;
}

std::string print_counters(const json&, const json& result) {
  return liftctl::format_counters(result);
}
std::string print_history(const json&, const json& result) {
  return liftctl::format_history(result);
}

Request request_key(const Args& args) {
  const auto key = args.size() == 2 ? parse_int(args[1]) : std::nullopt;
  if (!key) return bad_usage("usage: key N (N = 1..5)");
  return json{{"cmd", "key"}, {"key", *key}};
}

Request request_reset(const Args& args) {
  if (args.size() != 1) return bad_usage("reset takes no arguments");
  return json{{"cmd", "drive_reset"}};
}

Request request_power(const Args& args) {
  if (args.size() < 2 || args.size() > 3) return bad_usage("usage: power mains|emergency [SAVING]");
  json request = {{"cmd", "power"}, {"supply", args[1]}};
  if (args.size() == 3) {
    const auto saving = parse_int(args[2]);
    if (!saving) return bad_usage("power: SAVING must be 0, 1 or 2");
    request["saving"] = *saving;
  }
  return request;
}

Request request_load(const Args& args) {
  const auto percent = args.size() == 2 ? parse_int(args[1]) : std::nullopt;
  if (!percent) return bad_usage("usage: load PERCENT");
  return json{{"cmd", "load"}, {"percent", *percent}};
}

Request request_travel(const Args& args) {
  const auto floor = args.size() >= 2 ? parse_int(args[1]) : std::nullopt;
  if (!floor || args.size() > 3) return bad_usage("usage: travel FLOOR [V4|V3|...]");
  json request = {{"cmd", "travel"}, {"floor", *floor}};
  if (args.size() == 3) request["speed"] = args[2];
  return request;
}

/// stop, fast-stop, relevel: no arguments; the API spells fast-stop "fast_stop".
Request request_stop(const Args& args) {
  if (args.size() != 1) return bad_usage("this command takes no arguments");
  return json{{"cmd", args[0] == "fast-stop" ? "fast_stop" : args[0]}};
}

Request request_calls(const Args& args) {
  constexpr const char* kUsage =
      "usage: calls [add|cancel FLOOR | insert FLOOR [POSITION] | set [FLOOR...]]";
  json request = {{"cmd", "calls"}};
  if (args.size() == 1) return request;
  const std::string& action = args[1];
  std::vector<long> numbers;
  for (std::size_t i = 2; i < args.size(); ++i) {
    const auto n = parse_int(args[i]);
    if (!n) return bad_usage(kUsage);
    numbers.push_back(*n);
  }
  request["action"] = action;
  if ((action == "add" || action == "cancel") && numbers.size() == 1) {
    request["floor"] = numbers[0];
  } else if (action == "insert" && (numbers.size() == 1 || numbers.size() == 2)) {
    request["floor"] = numbers[0];
    if (numbers.size() == 2) request["position"] = numbers[1];
  } else if (action == "set") {
    request["floors"] = numbers;  // none: empty the queue
  } else {
    return bad_usage(kUsage);
  }
  return request;
}

Request request_inspection(const Args& args) {
  if (args.size() < 2 || args.size() > 3) return bad_usage("usage: inspection on|off [up|down]");
  json request = {{"cmd", "inspection"}, {"mode", args[1]}};
  if (args.size() == 3) request["direction"] = args[2];
  return request;
}

Request request_fast_start(const Args& args) {
  if (args.size() < 2) return bad_usage("usage: fast-start arm FLOOR|go|abort");
  json request = {{"cmd", "fast_start"}, {"action", args[1]}};
  if (args[1] == "arm") {
    const auto floor = args.size() == 3 ? parse_int(args[2]) : std::nullopt;
    if (!floor) return bad_usage("usage: fast-start arm FLOOR");
    request["floor"] = *floor;
  } else if (args.size() != 2) {
    return bad_usage("usage: fast-start arm FLOOR|go|abort");
  }
  return request;
}

/// uss-read and uss-write: PNU (and VALUE), then option words in any order.
Request request_uss_parameter(const Args& args) {
  const bool write = args[0] == "uss-write";
  const char* use = write ? "usage: uss-write PNU VALUE [dword] [eeprom] [array INDEX] [@ADDRESS]"
                          : "usage: uss-read PNU [array|description|text INDEX] [@ADDRESS]";
  const std::size_t first_option = write ? 3 : 2;
  const auto pnu = args.size() >= first_option ? parse_int(args[1]) : std::nullopt;
  if (!pnu) return bad_usage(use);
  json request = {{"cmd", write ? "uss_write" : "uss_read"}, {"pnu", *pnu}};
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
  return request;
}

Request request_uss_mirror(const Args& args) {
  json request = {{"cmd", "uss_mirror"}};
  if (args.size() > 2) return bad_usage("usage: uss-mirror [ADDRESS]");
  if (args.size() == 2) {
    const auto address = parse_int(args[1]);
    if (!address) return bad_usage("usage: uss-mirror [ADDRESS]");
    request["address"] = *address;
  }
  return request;
}

Request request_raw(const Args& args) {
  if (args.size() != 2) return bad_usage("usage: raw '{\"cmd\":...}'");
  json request = json::parse(args[1], nullptr, false);
  if (request.is_discarded() || !request.is_object()) {
    return bad_usage("raw: the argument must be one JSON object");
  }
  return request;
}

std::string print_status(const json&, const json& result) {
  return liftctl::format_status(result);
}
std::string print_stats(const json&, const json& result) {
  return liftctl::format_stats(result);
}
std::string print_trace(const json&, const json& result) {
  return liftctl::format_trace(result);
}
std::string print_display(const json&, const json& result) {
  return liftctl::format_display(result);
}
std::string print_config(const json&, const json& result) {
  return result.value("config", json::object()).dump(2) + "\n";
}
std::string print_generic(const json&, const json& result) {
  return liftctl::format_generic(result);
}

// ---- learn ----

/// How long `learn` waits for its reply: the learning travel crawls through the whole shaft.
constexpr int kLearnReplyTimeoutMs = 60 * 60 * 1000;

/// learn [--apply FILE]: FILE is the daemon's configuration file (liftctl cannot ask for it).
Request request_learn(const Args& args) {
  if (args.size() != 1 && !(args.size() == 3 && args[1] == "--apply")) {
    return bad_usage("usage: learn [--apply CONFIG_FILE]");
  }
  return json{{"cmd", "learn"}};
}

std::string print_learn(const json&, const json& result) {
  return liftctl::format_learn_result(result);
}

/// The learning travel: waits for its result, prints it, and with --apply writes it.
int run_learn(Connection& conn, const Args& args, json request, bool raw_json) {
  request["id"] = 1;
  if (!conn.send_line(request.dump())) return kExitNoDaemon;
  std::optional<json> reply;
  while (!reply) {
    auto message = conn.read_json(kLearnReplyTimeoutMs);
    if (!message) {
      std::fprintf(stderr, "liftctl: liftd closed the connection without answering\n");
      return kExitNoDaemon;
    }
    if (message->contains("ok")) reply = std::move(message);
  }
  if (reply->value("ok", false) != true) return report_error(*reply);
  const json result = reply->value("result", json::object());
  std::fputs(raw_json ? (result.dump(2) + "\n").c_str() : print_learn(request, result).c_str(),
             stdout);
  if (!result.value("accepted", false)) return kExitFailed;
  if (args.size() != 3) return kExitOk;
  const liftctl::ApplyOutcome outcome = liftctl::apply_learned_levels(args[2], result);
  std::fprintf(outcome.ok ? stdout : stderr, "%s%s\n",
               outcome.ok ? "" : "liftctl: ", outcome.message.c_str());
  return outcome.ok ? kExitOk : kExitFailed;
}

/// One subcommand: how its words become a request, and how the result is printed (watch and
/// raw print what they receive themselves).
struct Subcommand {
  const char* name;
  Request (*request)(const Args& args);
  std::string (*print)(const json& request, const json& result);
};

constexpr Subcommand kSubcommands[] = {
    {"status", request_plain, print_status},
    {"watch", request_watch, nullptr},
    {"stats", request_plain, print_stats},
    {"trace", request_trace, print_trace},
    {"plot", request_plot, nullptr},
    {"counters", request_counters, print_counters},
    {"history", request_history, print_history},
    {"display", request_plain, print_display},
    {"key", request_key, print_generic},
    {"reset", request_reset, print_generic},
    {"power", request_power, print_generic},
    {"load", request_load, print_generic},
    {"travel", request_travel, liftctl::format_travel_result},
    {"stop", request_stop, liftctl::format_travel_result},
    {"fast-stop", request_stop, liftctl::format_travel_result},
    {"relevel", request_stop, liftctl::format_travel_result},
    {"calls", request_calls, liftctl::format_travel_result},
    {"learn", request_learn, print_learn},
    {"inspection", request_inspection, liftctl::format_travel_result},
    {"fast-start", request_fast_start, liftctl::format_travel_result},
    {"uss-read", request_uss_parameter, print_generic},
    {"uss-write", request_uss_parameter, print_generic},
    {"uss-mirror", request_uss_mirror, print_generic},
    {"config", request_plain, print_config},
    {"version", request_plain, print_generic},
    {"raw", request_raw, nullptr},
};

/// Connects and waits for liftd's greeting; false (reported) when that fails.
bool connect_to_liftd(Connection& conn, const std::string& socket_path) {
  if (!conn.open(socket_path)) return false;
  const auto hello = conn.read_json(kReplyTimeoutMs);
  if (!hello || hello->value("event", "") != "hello") {
    if (hello && hello->contains("error")) {
      report_error(*hello);  // e.g. busy: too many clients
      return false;
    }
    std::fprintf(stderr, "liftctl: %s did not greet like liftd\n", socket_path.c_str());
    return false;
  }
  return true;
}

/// raw: the caller's id (if any) is kept; the reply is printed as received.
int run_raw(Connection& conn, const json& request) {
  if (!conn.send_line(request.dump())) return kExitNoDaemon;
  for (;;) {
    const auto message = conn.read_json(kReplyTimeoutMs);
    if (!message) return kExitNoDaemon;
    if (!message->contains("ok")) continue;
    std::printf("%s\n", message->dump().c_str());
    return message->value("ok", false) ? kExitOk : kExitFailed;
  }
}

/// Sends `request` and takes its result into `result`. Returns the exit status when the command
/// is done already: no daemon, a refusal (reported), or --json (the result printed).
std::optional<int> fetch_result(Connection& conn, const json& request, bool raw_json,
                                json& result) {
  const auto reply = call(conn, request);
  if (!reply) return kExitNoDaemon;
  if (reply->value("ok", false) != true) return report_error(*reply);
  result = reply->value("result", json::object());
  if (raw_json) {
    std::printf("%s\n", result.dump(2).c_str());
    return kExitOk;
  }
  return std::nullopt;
}

/// Every other subcommand: one request, its result printed by the subcommand (or as JSON).
int run_request(Connection& conn, const Subcommand& subcommand, const json& request,
                bool raw_json) {
  json result;
  if (const auto done = fetch_result(conn, request, raw_json, result)) return *done;
  std::fputs(subcommand.print(request, result).c_str(), stdout);
  return kExitOk;
}

/// plot: the chart on stdout, or the SVG document into --svg FILE.
int run_plot(Connection& conn, const Args& args, const json& request, bool raw_json) {
  std::string error;
  const bool trend = liftctl::wants_trend(args);
  std::optional<std::string> svg_path;
  if (trend) {
    svg_path = liftctl::trend_request(args, error)->svg_path;
  } else {
    svg_path = liftctl::parse_plot_args(args, error)->svg_path;
  }
  json result;
  if (const auto done = fetch_result(conn, request, raw_json, result)) return *done;
  if (!svg_path) {
    std::fputs((trend ? liftctl::format_trend(result) : liftctl::format_plot(result)).c_str(),
               stdout);
    return kExitOk;
  }
  std::FILE* file = std::fopen(svg_path->c_str(), "w");
  const std::string svg = trend ? liftctl::render_trend_svg(result) : liftctl::render_svg(result);
  bool written = file != nullptr && std::fwrite(svg.data(), 1, svg.size(), file) == svg.size();
  if (file != nullptr && std::fclose(file) != 0) written = false;
  if (!written) {
    std::fprintf(stderr, "liftctl: cannot write %s: %s\n", svg_path->c_str(), std::strerror(errno));
    return kExitFailed;
  }
  const std::size_t count = result.value(trend ? "days" : "travels", json::array()).size();
  std::printf(
      "%zu %s written to %s\n", count,
      trend ? (count == 1 ? "floor-day" : "floor-days") : (count == 1 ? "travel" : "travels"),
      svg_path->c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const auto exit_status = parse_options(argc, argv, options)) return *exit_status;
  const std::string& command = options.args[0];
  const Subcommand* subcommand = nullptr;
  for (const auto& candidate : kSubcommands) {
    if (command == candidate.name) {
      subcommand = &candidate;
      break;
    }
  }
  if (subcommand == nullptr) {
    std::fprintf(stderr, "liftctl: unknown command \"%s\"\n", command.c_str());
    usage(stderr);
    return kExitUsage;
  }
  const Request request = subcommand->request(options.args);
  if (!request) return kExitUsage;

  Connection conn;
  if (!connect_to_liftd(conn, options.socket_path)) return kExitNoDaemon;
  if (command == "watch") return run_watch(conn, options.raw_json);
  if (command == "raw") return run_raw(conn, *request);
  if (command == "plot") return run_plot(conn, options.args, *request, options.raw_json);
  if (command == "learn") return run_learn(conn, options.args, *request, options.raw_json);
  return run_request(conn, *subcommand, *request, options.raw_json);
}
