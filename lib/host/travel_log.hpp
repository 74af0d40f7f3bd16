// The last travels with their curves, for the API's `travels` (every drive kind alike): the io
// thread takes the samples the controller queues once per step (lift::TravelSample) and the
// travel events, and keeps the last kTravelsKept travels, each with its start, end, cause, target
// floor and samples. The names of the drive's command and status bits come from the kind's
// folder (TravelBitNames).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/mono_time.hpp"
#include "config/config.hpp"
#include "lift/travel_sample.hpp"

namespace liftd::daemon {

/// The names of the drive's command and status bits, by bit number (empty: a bit not shown).
struct TravelBitNames {
  std::vector<std::string> command;
  std::vector<std::string> status;
};

/// One travel as the log keeps it.
struct RecordedTravel {
  std::uint64_t id = 0;  ///< counts the travels since the daemon started, from 1
  std::string kind;      ///< the run's kind (status travel.state names)
  MonoTime start{};
  MonoTime end{};
  bool ended = false;
  std::optional<std::string> cause;  ///< "arrived" or the abort cause; none while unknown
  std::optional<std::size_t> target_floor;
  /// Every `stride`-th sample of the run: a run longer than kMaxSamples samples keeps every
  /// second one, then every fourth, so the whole run stays in the curve.
  std::vector<lift::TravelSample> samples;
  std::size_t stride = 1;
  std::uint64_t seen = 0;  ///< samples of the run taken so far
};

class TravelLog {
 public:
  static constexpr std::size_t kTravelsKept = 16;
  /// 60 s of 15 ms DCP cycles (DCP 7.2).
  static constexpr std::size_t kMaxSamples = 4000;
  static constexpr std::size_t kDefaultLast = 5;

  TravelLog(TravelBitNames names, std::vector<std::int64_t> floors_mm);

  /// A sample from the controller's queue, in the order they were taken.
  void add(const lift::TravelSample& sample);
  /// A travel ended at `at`: `cause` "arrived" or the abort cause's API name.
  void end(MonoTime at, std::string_view cause);
  /// Takes every sample `controller` queued (its poll_travel_sample()) and its drop count.
  template <typename Controller>
  void drain(Controller& controller) {
    lift::TravelSample s;
    while (controller.poll_travel_sample(s)) add(s);
    dropped_ = controller.dropped_travel_samples();
  }

  /// The `travels` result: the newest `last` travels, oldest first, each with its samples.
  nlohmann::json to_json(
      std::size_t last,
      const std::function<std::chrono::system_clock::time_point(MonoTime)>& wall) const;

  const std::deque<RecordedTravel>& travels() const noexcept { return travels_; }

  /// Called once for each travel when both its last sample and its end's cause are in (the
  /// lift's record keeps it).
  void set_completion_listener(std::function<void(const RecordedTravel&)> listener) {
    on_complete_ = std::move(listener);
  }
  /// One travel's curve, compact: one array per column ({"t_ms":[..],"position_mm":[..],
  /// "speed_mm_s":[..],"remaining_mm":[..],"command":[..],"status":[..]}, unknown values null,
  /// the bits as integers with the names in "command_bits"/"status_bits").
  nlohmann::json curve_columns(const RecordedTravel& t) const;

 private:
  void append(RecordedTravel& t, const lift::TravelSample& sample);
  void complete(const RecordedTravel& t) const {
    if (on_complete_) on_complete_(t);
  }
  nlohmann::json sample_json(const RecordedTravel& t, const lift::TravelSample& s) const;

  TravelBitNames names_;
  std::vector<std::int64_t> floors_mm_;
  std::deque<RecordedTravel> travels_;
  std::uint32_t current_run_ = 0;
  bool in_run_ = false;
  std::uint64_t next_id_ = 1;
  /// An end told before the run's first sample arrived.
  std::optional<std::pair<MonoTime, std::string>> pending_end_;
  std::uint64_t dropped_ = 0;
  std::function<void(const RecordedTravel&)> on_complete_;
};

/// The floors' levels (config `floors`), for the target's level.
std::vector<std::int64_t> floor_levels_mm(const config::Config& config);

/// "arrived" for a finished travel, else the abort cause's API name (lift::to_string).
std::string travel_end_cause(bool aborted, std::string_view cause_name);

}  // namespace liftd::daemon
