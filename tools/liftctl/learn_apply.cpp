#include "learn_apply.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace liftctl {

namespace {

using ordered = nlohmann::ordered_json;

std::string pad(const std::string& text, std::size_t width, bool right) {
  if (text.size() >= width) return text;
  const std::string fill(width - text.size(), ' ');
  return right ? fill + text : text + fill;
}

std::string number(const nlohmann::json& value) {
  return value.is_number_integer() ? std::to_string(value.get<long long>()) : "-";
}

std::string failure(const std::string& what, int error) {
  return what + ": " + std::strerror(error);
}

/// Writes all of `text` to `fd` and flushes it to disk.
bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return ::fsync(fd) == 0;
}

/// Writes `text` to a new file in `path`'s directory with `mode`, flushed; its name, or empty
/// (errno set) when that fails.
std::string write_temporary(const std::string& path, const std::string& text, mode_t mode) {
  std::vector<char> name(path.begin(), path.end());
  const std::string suffix = ".learn-XXXXXX";
  name.insert(name.end(), suffix.begin(), suffix.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) return {};
  const bool written = ::fchmod(fd, mode) == 0 && write_all(fd, text);
  const int error = errno;
  ::close(fd);
  if (!written) {
    ::unlink(name.data());
    errno = error;
    return {};
  }
  return std::string(name.data());
}

std::string directory_of(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

}  // namespace

std::string format_learn_result(const nlohmann::json& result) {
  std::ostringstream out;
  out << pad("floor", 6, false) << pad("name", 12, false) << pad("configured", 11, true)
      << pad("learned", 10, true) << pad("difference", 12, true) << pad("zone", 7, true) << "\n";
  for (const auto& f : result.value("floors", nlohmann::json::array())) {
    out << pad(number(f.value("floor", nlohmann::json())), 6, false)
        << pad(f.value("name", ""), 12, false)
        << pad(number(f.value("configured_mm", nlohmann::json())) + " mm", 11, true)
        << pad(number(f.value("learned_mm", nlohmann::json())) + " mm", 10, true)
        << pad(number(f.value("difference_mm", nlohmann::json())) + " mm", 12, true)
        << pad(number(f.value("zone_mm", nlohmann::json())) + " mm", 7, true) << "\n";
  }
  out << (result.value("accepted", false) ? "accepted: " : "refused: ")
      << result.value("reason", "") << "\n";
  if (result.contains("takes_effect")) out << result.value("takes_effect", "") << "\n";
  return out.str();
}

ApplyOutcome apply_learned_levels(const std::string& path, const nlohmann::json& result) {
  if (!result.value("accepted", false)) {
    return {false,
            "not applied: the learning travel was refused (" + result.value("reason", "") + ")"};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return {false, failure("cannot read " + path, errno)};
  std::stringstream old_text;
  old_text << in.rdbuf();
  ordered config = ordered::parse(old_text.str(), nullptr, false);
  if (config.is_discarded() || !config.is_object()) {
    return {false, path + " is not a JSON object: nothing written"};
  }
  const auto& learned = result.at("floors");
  if (!config.contains("floors") || !config["floors"].is_array() ||
      config["floors"].size() != learned.size()) {
    return {false, path + "'s floors are not the " + std::to_string(learned.size()) +
                       " floors liftd learned: nothing written"};
  }
  for (std::size_t i = 0; i < learned.size(); ++i) {
    ordered& floor = config["floors"][i];
    if (!floor.is_object() ||
        floor.value("level_mm", ordered()) != ordered(learned[i].at("configured_mm"))) {
      return {false, path + "'s floor " + std::to_string(i) +
                         " is not at the level liftd runs with: nothing written"};
    }
  }
  for (std::size_t i = 0; i < learned.size(); ++i) {
    config["floors"][i]["level_mm"] = learned[i].at("learned_mm").get<long long>();
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {false, failure("cannot stat " + path, errno)};
  const mode_t mode = st.st_mode & 07777;
  const std::string backup = path + ".bak";
  const std::string backup_tmp = write_temporary(backup, old_text.str(), mode);
  if (backup_tmp.empty() || ::rename(backup_tmp.c_str(), backup.c_str()) != 0) {
    const int error = errno;
    if (!backup_tmp.empty()) ::unlink(backup_tmp.c_str());
    return {false, failure("cannot keep the old file as " + backup + ", nothing written", error)};
  }
  const std::string fresh = write_temporary(path, config.dump(2) + "\n", mode);
  if (fresh.empty()) return {false, failure("cannot write beside " + path, errno)};
  if (::rename(fresh.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(fresh.c_str());
    return {false, failure("cannot replace " + path, error)};
  }
  // The rename itself reaches the disk with the directory.
  const int dir = ::open(directory_of(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    (void)::fsync(dir);
    ::close(dir);
  }
  return {true, "wrote the learned levels of " + std::to_string(learned.size()) + " floors to " +
                    path + " (the old file is " + backup + ")"};
}

}  // namespace liftctl
