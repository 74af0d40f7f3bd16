// Loading: the file, the JSON text, the document against a Schema, and the host checks.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "common/cpu_set.hpp"
#include "config/schema.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;

std::string join_quoted(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += ", ";
    out += json_quoted(item);
  }
  return out;
}

std::vector<std::string> known_paths_and_sections(const Schema& schema) {
  std::vector<std::string> out;
  for (const auto& key : schema.keys()) {
    out.push_back(key.path);
    const auto dot = key.path.find('.');
    if (dot != std::string::npos) {
      std::string section = key.path.substr(0, dot);
      if (std::find(out.begin(), out.end(), section) == out.end()) out.push_back(section);
    }
  }
  return out;
}

bool is_section(const Schema& schema, const std::string& name) {
  return std::any_of(schema.keys().begin(), schema.keys().end(),
                     [&](const Key& k) { return k.path.rfind(name + ".", 0) == 0; });
}

bool is_leaf(const Schema& schema, const std::string& path) {
  return std::any_of(schema.keys().begin(), schema.keys().end(),
                     [&](const Key& k) { return k.path == path; });
}

// Reports unknown keys and sections that are not objects.
void find_unknown(const json& object, const std::string& prefix, const Schema& schema,
                  Problems& problems) {
  const std::vector<std::string> pool = known_paths_and_sections(schema);
  for (const auto& [name, value] : object.items()) {
    const std::string path = prefix.empty() ? name : prefix + "." + name;
    if (is_leaf(schema, path)) continue;
    if (is_section(schema, path)) {
      if (value.is_object()) {
        find_unknown(value, path, schema, problems);
      } else {
        problems.push_back({path, "expected an object (a section), got " + show(value)});
      }
      continue;
    }
    problems.push_back({path, "unknown key" + did_you_mean(path, pool)});
  }
}

void apply_key(const Key& key, const json& value, Config& config, Problems& problems) {
  switch (key.type) {
    case Type::boolean:
      if (!value.is_boolean()) {
        problems.push_back({key.path, "expected true or false, got " + show(value)});
        return;
      }
      break;
    case Type::integer:
      if (!check_integer(value, key.path, key.min, key.max, problems)) return;
      break;
    case Type::string: {
      if (!value.is_string()) {
        problems.push_back({key.path, "expected a string, got " + show(value)});
        return;
      }
      const auto text = value.get<std::string>();
      const auto length = static_cast<std::int64_t>(text.size());
      if (length < key.min || length > key.max) {
        problems.push_back({key.path, show(value) + " has " + std::to_string(length) +
                                          " bytes: allowed " + std::to_string(key.min) + ".." +
                                          std::to_string(key.max)});
        return;
      }
      if (key.check) {
        const std::string why = key.check(text);
        if (!why.empty()) {
          problems.push_back({key.path, show(value) + " " + why});
          return;
        }
      }
      break;
    }
    case Type::choice:
      if (!value.is_string() || std::find(key.choices.begin(), key.choices.end(),
                                          value.get<std::string>()) == key.choices.end()) {
        problems.push_back(
            {key.path, show(value) + " is not allowed: use one of " + join_quoted(key.choices) +
                           (value.is_string() ? did_you_mean(value.get<std::string>(), key.choices)
                                              : std::string{})});
        return;
      }
      break;
    case Type::floors:
    case Type::speed_map:
    case Type::custom:
      key.custom(value, key.path, config, problems);
      return;
  }
  key.set(config, value);
}

// 1-based line and column of a byte offset, for parse errors.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

}  // namespace

LoadResult from_json(const json& document, const Schema& schema) {
  LoadResult result;
  if (!document.is_object()) {
    result.problems.push_back({"(top level)", "expected a JSON object, got " + show(document)});
    return result;
  }
  find_unknown(document, "", schema, result.problems);
  for (const auto& key : schema.keys()) {
    if (const json* value = find_value(document, key.path)) {
      apply_key(key, *value, result.config, result.problems);
    }
  }
  // A valid speed count with the default distances can still disagree: check them together.
  if (find_value(document, "travel.dcp3_decel_distance_mm") == nullptr &&
      find_value(document, "travel.dcp3_speed_count") != nullptr) {
    for (const auto& key : schema.keys()) {
      if (key.type == Type::speed_map) {
        apply_key(key, key.get(result.config), result.config, result.problems);
      }
    }
  }
  check_shared_keys(result.config, document, result.problems);
  // A kind's own cross-check runs only for the kind in use: a file may keep the sections of
  // other kinds, checked for type and range above.
  const KindRules* kind = schema.rules_of(result.config.drive.kind);
  if (kind != nullptr && kind->check) kind->check(result.config, document, result.problems);
  return result;
}

LoadResult parse(std::string_view text, std::string_view origin, const Schema& schema) {
  // Track the keys of each open object to report duplicates, which JSON parsers drop silently.
  struct Frame {
    bool is_object;
    std::vector<std::string> keys;
    std::string name;
  };
  std::vector<Frame> stack;
  std::string pending_key;
  Problems duplicates;
  const auto path_of = [&](const std::string& key) {
    std::string out;
    for (const auto& f : stack) {
      if (!f.name.empty()) out += (out.empty() ? "" : ".") + f.name;
    }
    return out.empty() ? key : out + "." + key;
  };
  const json::parser_callback_t callback = [&](int /*depth*/, json::parse_event_t event,
                                               json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        stack.push_back({event == json::parse_event_t::object_start, {}, pending_key});
        pending_key.clear();
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!stack.empty()) stack.pop_back();
        break;
      case json::parse_event_t::key: {
        const auto key = parsed.get<std::string>();
        if (!stack.empty() && stack.back().is_object) {
          auto& keys = stack.back().keys;
          if (std::find(keys.begin(), keys.end(), key) != keys.end()) {
            duplicates.push_back({path_of(key), "duplicate key: only one value is allowed"});
          }
          keys.push_back(key);
        }
        pending_key = key;
        break;
      }
      case json::parse_event_t::value:
        pending_key.clear();
        break;
    }
    return true;
  };
  json document;
  try {
    document = json::parse(text.begin(), text.end(), callback, true, false);
  } catch (const json::parse_error& error) {
    const auto [line, column] = line_column(text, error.byte == 0 ? 0 : error.byte - 1);
    std::string what = error.what();
    // nlohmann's text starts with "[json.exception.parse_error.101] parse error at line ..:";
    // keep only the part after the last ": " (what was expected and found).
    const auto colon = what.rfind(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    LoadResult result;
    result.problems.push_back(
        {std::string(origin) + ":" + std::to_string(line) + ":" + std::to_string(column),
         "malformed JSON: " + what});
    return result;
  } catch (const json::exception& error) {
    // out_of_range 406: a number too large for any JSON number type (e.g. 1E989299). The
    // library gives no position for it.
    LoadResult result;
    result.problems.push_back(
        {std::string(origin), error.id == 406 ? "malformed JSON: a number is too large to represent"
                                              : std::string("malformed JSON: ") + error.what()});
    return result;
  }
  LoadResult result = from_json(document, schema);
  result.problems.insert(result.problems.begin(), duplicates.begin(), duplicates.end());
  return result;
}

namespace {

std::string file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return std::strerror(EISDIR);  // "Is a directory", as read() would say
  if (S_ISFIFO(mode)) return "it is a FIFO";
  if (S_ISCHR(mode)) return "it is a character device";
  if (S_ISBLK(mode)) return "it is a block device";
  if (S_ISSOCK(mode)) return "it is a socket";
  return "it is of an unknown type";
}

}  // namespace

LoadResult load_file(const std::filesystem::path& path, const Schema& schema) {
  const auto problem = [&](std::string message) {
    LoadResult result;
    result.problems.push_back({path.string(), std::move(message)});
    return result;
  };
  const auto unreadable = [&](int error) {
    return problem(std::string("cannot read the config file: ") + std::strerror(error));
  };
  const auto not_regular = [&](mode_t mode) {
    return problem("cannot read the config file: " + file_type_name(mode) +
                   "; only a regular file is read");
  };
  const auto too_large = [&]() {
    return problem("cannot read the config file: it is larger than " +
                   std::to_string(kMaxFileBytes) + " bytes");
  };
  // Look before opening: opening a device can have effects (a serial port drops DTR) and a FIFO
  // blocks. Symbolic links are followed (a config under /etc may well be one).
  struct stat before {};
  if (::stat(path.c_str(), &before) != 0) return unreadable(errno);
  if (!S_ISREG(before.st_mode)) return not_regular(before.st_mode);
  // O_NONBLOCK: should the path become a FIFO between stat() and open(), open() still returns;
  // fstat() then tells what was really opened.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return unreadable(errno);
  struct stat opened {};
  if (::fstat(fd, &opened) != 0) {
    const int error = errno;
    ::close(fd);
    return unreadable(error);
  }
  if (!S_ISREG(opened.st_mode)) {
    ::close(fd);
    return not_regular(opened.st_mode);
  }
  if (static_cast<std::uintmax_t>(opened.st_size) > kMaxFileBytes) {
    ::close(fd);
    return too_large();
  }
  std::string text;
  char buffer[4096];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n < 0) {
      const int error = errno;
      if (error == EINTR) continue;
      ::close(fd);
      return unreadable(error);
    }
    if (n == 0) break;
    // The file may grow while we read it: the limit holds for what is read, too.
    if (text.size() + static_cast<std::size_t>(n) > kMaxFileBytes) {
      ::close(fd);
      return too_large();
    }
    text.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  LoadResult result = parse(text, path.string(), schema);
  const Problems host = check_host(result.config, HostFacts::current());
  result.problems.insert(result.problems.end(), host.begin(), host.end());
  return result;
}

HostFacts HostFacts::current() {
  HostFacts facts;
  // The affinity mask holds only CPUs that are online and that this process (its cgroup's
  // cpuset, the unit's CPUAffinity=) may use: exactly where the cycle thread can be pinned.
  facts.usable_cpus = current_cpus();
  return facts;
}

std::vector<Problem> check_host(const Config& config, const HostFacts& host) {
  Problems problems;
  if (config.rt.cpu >= 0 && std::find(host.usable_cpus.begin(), host.usable_cpus.end(),
                                      config.rt.cpu) == host.usable_cpus.end()) {
    const std::string usable = cpu_list_text(host.usable_cpus);
    problems.push_back({"rt.cpu", std::to_string(config.rt.cpu) +
                                      " is not a CPU this machine lets liftd run on: use -1 or "
                                      "one of " +
                                      (usable.empty() ? std::string("(none found)") : usable)});
  }
  return problems;
}

}  // namespace liftd::config
