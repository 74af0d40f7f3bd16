// Flight-recorder files in the runtime directory: created safely, capped in number, and saved on
// request at a limited rate. The directory is a RAM file system under systemd, and anyone able
// to plant a symbolic link there must not make liftd write elsewhere.
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace liftd::daemon {

/// The outcome of TraceFiles::write: the path written, or what went wrong.
struct TraceWrite {
  std::string path;   ///< the new file, when written
  std::string error;  ///< why not, when empty path
  /// Files removed to stay within the cap.
  std::vector<std::string> removed;
  /// True when the file was written.
  bool ok() const { return error.empty(); }
};

/// Writes liftd-trace-<stamp>.txt files into one directory.
class TraceFiles {
 public:
  /// Shortest time between two saves asked for through the API (a fault's own save is never
  /// refused): one every 10 s is plenty for a technician and keeps a client from filling RAM.
  static constexpr std::chrono::seconds kRequestInterval{10};

  /// Files go to `dir`; at most `keep` of them stay (the oldest are removed first).
  TraceFiles(std::string dir, std::size_t keep);

  /// Nothing when an API request may save now (and records it), or why it must wait.
  std::optional<std::string> admit_request(std::chrono::steady_clock::time_point now);

  /// Creates a new file `liftd-trace-<stamp>.txt` (or `...-<stamp>-2.txt`, ... when that name
  /// is taken) with `text`, then removes the oldest trace files beyond the cap. The file is
  /// created with O_CREAT|O_EXCL|O_NOFOLLOW relative to the directory opened with O_NOFOLLOW,
  /// and only in a directory owned by this process's user that no group or other may write.
  TraceWrite write(std::string_view stamp, std::string_view text);

  /// The directory.
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::size_t keep_;
  std::optional<std::chrono::steady_clock::time_point> last_request_;
};

}  // namespace liftd::daemon
