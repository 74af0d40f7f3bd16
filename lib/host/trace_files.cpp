// Flight-recorder files: safe creation, a cap on their number, a rate limit on requests.
#include "host/trace_files.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <sstream>
#include <utility>

#include "log/log.hpp"

namespace liftd::daemon {
namespace {

constexpr std::string_view kPrefix = "liftd-trace-";
constexpr std::string_view kSuffix = ".txt";
// Names tried when the second's name is taken: "-2" .. "-9".
constexpr int kMaxSameSecond = 9;

std::string errno_text(int error) {
  return std::strerror(error);
}

bool is_trace_name(std::string_view name) {
  return name.size() > kPrefix.size() + kSuffix.size() && name.starts_with(kPrefix) &&
         name.ends_with(kSuffix);
}

// Writes all of `text` to `fd`; 0 or an errno.
int write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return 0;
}

struct Entry {
  std::string name;
  timespec modified{};
};

}  // namespace

TraceFiles::TraceFiles(std::string dir, std::size_t keep) : dir_(std::move(dir)), keep_(keep) {}

std::optional<std::string> TraceFiles::admit_request(std::chrono::steady_clock::time_point now) {
  if (last_request_ && now - *last_request_ < kRequestInterval) {
    const auto wait =
        std::chrono::ceil<std::chrono::seconds>(kRequestInterval - (now - *last_request_));
    return "a trace was saved less than " + std::to_string(kRequestInterval.count()) +
           " s ago; try again in " + std::to_string(wait.count()) + " s";
  }
  last_request_ = now;
  return std::nullopt;
}

TraceWrite TraceFiles::write(std::string_view stamp, std::string_view text) {
  TraceWrite out;
  const int dir_fd = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (dir_fd < 0) {
    out.error = "cannot open the directory " + dir_ + ": " + errno_text(errno);
    return out;
  }
  struct stat st {};
  if (::fstat(dir_fd, &st) != 0 || st.st_uid != ::geteuid() ||
      (st.st_mode & (S_IWGRP | S_IWOTH)) != 0) {
    ::close(dir_fd);
    out.error = "not writing into " + dir_ +
                ": the directory must belong to liftd's user and be writable by nobody else";
    return out;
  }
  int fd = -1;
  std::string name;
  for (int n = 1; n <= kMaxSameSecond && fd < 0; ++n) {
    name = std::string(kPrefix) + std::string(stamp) + (n == 1 ? "" : "-" + std::to_string(n)) +
           std::string(kSuffix);
    fd = ::openat(dir_fd, name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0640);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) {
    out.error = "cannot create " + dir_ + "/" + name + ": " + errno_text(errno);
    ::close(dir_fd);
    return out;
  }
  const int error = write_all(fd, text);
  ::close(fd);
  if (error != 0) {
    ::unlinkat(dir_fd, name.c_str(), 0);
    ::close(dir_fd);
    out.error = "cannot write " + dir_ + "/" + name + ": " + errno_text(error);
    return out;
  }
  out.path = dir_ + "/" + name;

  // Keep the newest `keep_` trace files (regular files only; links and others are left alone).
  std::vector<Entry> entries;
  if (const int list_fd = ::openat(dir_fd, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC); list_fd >= 0) {
    if (DIR* d = ::fdopendir(list_fd)) {
      while (const dirent* e = ::readdir(d)) {
        const std::string_view entry_name(e->d_name);
        if (!is_trace_name(entry_name)) continue;
        struct stat es {};
        if (::fstatat(dir_fd, e->d_name, &es, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(es.st_mode)) {
          continue;
        }
        entries.push_back({std::string(entry_name), es.st_mtim});
      }
      ::closedir(d);
    } else {
      ::close(list_fd);
    }
  }
  if (entries.size() > keep_) {
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
      if (a.modified.tv_sec != b.modified.tv_sec) return a.modified.tv_sec < b.modified.tv_sec;
      if (a.modified.tv_nsec != b.modified.tv_nsec) return a.modified.tv_nsec < b.modified.tv_nsec;
      return a.name < b.name;
    });
    const std::size_t excess = entries.size() - keep_;
    for (std::size_t i = 0; i < excess; ++i) {
      if (entries[i].name == name) continue;  // never the one just written
      if (::unlinkat(dir_fd, entries[i].name.c_str(), 0) == 0) {
        out.removed.push_back(dir_ + "/" + entries[i].name);
      }
    }
  }
  ::close(dir_fd);
  return out;
}

FlightRecorderFiles::FlightRecorderFiles(const rt::FlightRecorder& recorder, std::string dir,
                                         std::size_t keep, std::string component,
                                         DecoderSource decoder)
    : recorder_(recorder),
      files_(std::move(dir), keep),
      keep_(keep),
      component_(std::move(component)),
      decoder_(std::move(decoder)) {}

api::Result FlightRecorderFiles::save_requested(std::chrono::steady_clock::time_point now) {
  if (const auto wait = files_.admit_request(now)) {
    return api::Result::fail(api::ErrorCode::Busy, *wait);
  }
  return write("request");
}

api::Result FlightRecorderFiles::write(std::string_view why) {
  const std::vector<rt::FrameRecord> records = recorder_.copy();
  char stamp[32];
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  std::ostringstream text_out;
  rt::write_text(text_out, records, decoder_ ? decoder_() : rt::FrameDecoder{});
  const TraceWrite written = files_.write(stamp, text_out.str());
  if (!written.ok()) {
    const std::string text = "could not write the flight recorder: " + written.error;
    log::event(log::Level::warn, component_, "trace_not_written", {{"dir", files_.dir()}}, text);
    return api::Result::fail(api::ErrorCode::Internal, text);
  }
  const std::string& path = written.path;
  for (const auto& old : written.removed) {
    log::event(log::Level::info, component_, "trace_removed", {{"path", old}},
               "removed the old flight recorder " + old + " (rt.trace_files_kept " +
                   std::to_string(keep_) + ")");
  }
  std::size_t bad = 0;
  for (const auto& r : records) {
    if ((r.flags & (rt::record_flag::kMissing | rt::record_flag::kBad)) != 0) ++bad;
  }
  log::event(log::Level::warn, component_, "trace_written",
             {{"path", path},
              {"records", std::to_string(records.size())},
              {"bad_or_missing", std::to_string(bad)}},
             "flight recorder (" + std::to_string(records.size()) + " records, " +
                 std::to_string(bad) + " bad or missing replies) written to " + path + " after " +
                 std::string(why));
  return api::Result::ok({{"file", path}, {"records", records.size()}});
}

std::vector<api::TraceEntry> trace_exchanges(const std::vector<rt::FrameRecord>& records,
                                             std::size_t max_entries, const TracePairing& pairing) {
  std::vector<api::TraceEntry> out;
  const rt::FrameRecord* before = nullptr;  // the other side's last frame since our last
  for (const rt::FrameRecord& r : records) {
    if (r.direction == rt::Direction::Tx) {
      if (pairing.ours != nullptr && !pairing.ours(r)) continue;
      api::TraceEntry e;
      e.at = r.time;
      e.tx.assign(r.data().begin(), r.data().end());
      if (pairing.we_answer && before != nullptr) {
        e.rx.emplace(before->data().begin(), before->data().end());
      }
      before = nullptr;
      out.push_back(std::move(e));
    } else if (r.direction == rt::Direction::Rx &&
               (pairing.theirs == nullptr || pairing.theirs(r))) {
      if (pairing.we_answer) {
        before = &r;
      } else if (!out.empty() && !out.back().rx) {
        out.back().rx.emplace(r.data().begin(), r.data().end());
      }
    }
  }
  if (out.size() > max_entries) {
    out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(max_entries));
  }
  return out;
}

}  // namespace liftd::daemon
