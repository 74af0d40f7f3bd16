// Flight-recorder files in the runtime directory: created safely, capped in number, and saved on
// request at a limited rate. The directory is a RAM file system under systemd, and anyone able
// to plant a symbolic link there must not make liftd write elsewhere. FlightRecorderFiles is how
// every drive kind writes its recorder there (the API's `trace` with `save`, SIGUSR1, and on a
// DCP link fault).
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "api/backend.hpp"
#include "api/result.hpp"
#include "rt/flight_recorder.hpp"

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

/// One drive's flight recorder written to TraceFiles, alike for every drive kind: the records as
/// rt::write_text() lines (with the drive's decoded column where it has a decoder) in a new
/// liftd-trace-<UTC time>.txt, journalled under the drive's component as `trace_written`
/// (`trace_removed` for each old file beyond the cap, `trace_not_written` when it failed).
class FlightRecorderFiles {
 public:
  /// Makes the decoder of the next file (the DCP decoder follows the negotiated protocol); an
  /// empty source, or an empty decoder, writes no decoded column.
  using DecoderSource = std::function<rt::FrameDecoder()>;

  /// Files of `recorder` go to `dir`, at most `keep` of them stay; `component` is the journal's
  /// (the drive kind: "dcp", "sch001", "uss").
  FlightRecorderFiles(const rt::FlightRecorder& recorder, std::string dir, std::size_t keep,
                      std::string component, DecoderSource decoder = {});

  /// The API's `trace` with `save`: `busy` when the last such request was less than
  /// TraceFiles::kRequestInterval ago, else write("request").
  api::Result save_requested(std::chrono::steady_clock::time_point now);
  /// Writes the whole recorder to a new file and journals it "after `why`". The result holds
  /// `file` and `records`, or `internal` with the reason it was not written.
  api::Result write(std::string_view why);

  /// The directory.
  const std::string& dir() const { return files_.dir(); }

 private:
  const rt::FlightRecorder& recorder_;
  TraceFiles files_;
  std::size_t keep_;
  std::string component_;
  DecoderSource decoder_;
};

/// How a drive's recorded frames pair into the API's `trace` exchanges: which frames of ours
/// and which frames of the other side count, and on which side of ours the other's frame is.
struct TracePairing {
  /// Ours are answered (DCP, USS: the drive's reply follows the master's frame) or we answer
  /// (SCH001: liftd's frame answers the card's status that came before it).
  bool we_answer = false;
  /// Which sent frames are exchanges (nullptr: every one).
  bool (*ours)(const rt::FrameRecord&) = nullptr;
  /// Which received frames are the other side's part of one (nullptr: every one).
  bool (*theirs)(const rt::FrameRecord&) = nullptr;
};

/// The newest `max_entries` exchanges of `records` (a recorder's copy, oldest first), oldest
/// first: each frame of ours with the other side's frame it pairs with, if any (the first
/// after it, or the last before it when `we_answer`).
std::vector<api::TraceEntry> trace_exchanges(const std::vector<rt::FrameRecord>& records,
                                             std::size_t max_entries, const TracePairing& pairing);

}  // namespace liftd::daemon
