// The learning travel's sequence, once for every drive kind (issue 27, docs/api.md `learn`): the
// car goes below the bottom level (the approach, leg Down), then up at the drive's learning speed
// through every level zone (leg Up) while a LevelLearner records the zones; once every floor's
// zone is passed the car is stopped kLearnRunOutMm beyond the last one. `stop` and any fault end
// it and nothing is learned; a finished learning publishes its record.
//
// A drive kind supplies only how a leg runs: "start a learning leg to target_mm in direction at
// the learning speed" (DCP: a crawl travel at V0 by position; SCH001: the slow speed of the
// hydraulic unit; USS: the crawl setpoint) and "end the crawl at position P". Sans-I/O and
// fixed-size: it runs in the real-time thread (no allocation, lock, log or exception).
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "lift/cause.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"
#include "lift/level_learner.hpp"
#include "lift/rules.hpp"

namespace liftd::lift {

/// The car goes this far beyond each terminal level to begin and end outside its level zone:
/// half the longest plausible zone (kMaxLevelZoneMm) plus 100 mm for a configured terminal level
/// that far off its true level.
inline constexpr std::int64_t kLearnApproachMm = kMaxLevelZoneMm / 2 + 100;
/// After the last zone the car goes on this far before the leg is ended.
inline constexpr std::int64_t kLearnRunOutMm = 20;
/// A learning leg's run-time limit: the drive's own limit plus this many ms per mm of the leg
/// (25 mm/s, half the usual crawl or levelling speed of 0.05 m/s).
inline constexpr std::uint32_t kLearnMsPerMm = 40;

/// The run-time limit of a learning leg `distance_mm` long: `base_ms` (the drive's limit of a
/// crawl or a travel) plus kLearnMsPerMm per mm.
constexpr std::uint32_t learn_leg_limit_ms(std::uint32_t base_ms,
                                           std::int64_t distance_mm) noexcept {
  const std::int64_t mm = distance_mm < 0 ? -distance_mm : distance_mm;
  return base_ms + static_cast<std::uint32_t>(mm) * kLearnMsPerMm;
}

/// The longest a learning travel may take between `bottom_level_mm` and `top_level_mm` with legs
/// limited from `base_ms`: two legs through the whole shaft and both approaches.
constexpr std::chrono::milliseconds learn_longest(std::uint32_t base_ms,
                                                  std::int64_t bottom_level_mm,
                                                  std::int64_t top_level_mm) noexcept {
  const std::int64_t shaft_mm = top_level_mm - bottom_level_mm + 2 * kLearnApproachMm;
  return std::chrono::milliseconds(
      2 * static_cast<std::int64_t>(learn_leg_limit_ms(base_ms, shaft_mm)));
}

/// The reply texts of the learning travel (docs/api.md `learn`).
inline constexpr std::string_view kLearnStopped = "learning travel stopped: nothing learned";
inline constexpr std::string_view kLearnNotTaken = "the drive did not take the learning travel";
inline constexpr std::string_view kLearnRunning = "a learning travel is running";
inline constexpr std::string_view kLearnNoPosition =
    "no car position: the learning travel records by position";

/// What a learning travel found, published once when it ends well (its reply is ok).
struct LearnRecord {
  std::uint32_t tag = 0;  ///< the learn command's tag
  LearnJudgement judgement{};
  std::size_t zones_seen = 0;
  std::size_t zone_count = 0;  ///< zones stored (at most kMaxFloors)
  std::array<LearnedZone, kMaxFloors> zones{};
};

/// The learning travel's legs, its stop and its record.
class LearningTravel {
 public:
  enum class Phase : std::uint8_t {
    Idle,  ///< no learning travel
    Down,  ///< the approach to below the bottom level
    Up,    ///< up at the learning speed through every zone
  };

  Phase phase() const noexcept { return phase_; }
  bool active() const noexcept { return phase_ != Phase::Idle; }
  /// The learn command's tag (the reply's).
  std::uint32_t tag() const noexcept { return tag_; }
  /// The record of the last learning that ended well.
  const LearnRecord& record() const noexcept { return record_; }

  /// Where the approach goes: kLearnApproachMm below the bottom level.
  static std::int64_t bottom_mm(const FloorTable& floors) noexcept {
    return floors.level_mm(0) - kLearnApproachMm;
  }
  /// Where the leg up goes at most: kLearnApproachMm above the top level.
  static std::int64_t top_mm(const FloorTable& floors) noexcept {
    return floors.level_mm(floors.size() - 1) + kLearnApproachMm;
  }

  /// Begins a learning travel for the command `tag`, the car at `position_mm`: the leg up at once
  /// when the car stands within `tolerance_mm` of bottom_mm() or below it, else the approach.
  /// `start_leg(target_mm, direction)` starts a leg (true: it runs). True when a leg started.
  template <typename StartLeg>
  bool begin(std::uint32_t tag, const FloorTable& floors, std::int64_t position_mm,
             std::uint32_t tolerance_mm, StartLeg&& start_leg) noexcept {
    learner_.reset();
    tag_ = tag;
    leg_ended_ = false;
    leg_cause_ = Cause::None;
    stopped_ = false;
    run_out_ = false;
    const bool below = position_mm <= bottom_mm(floors) + static_cast<std::int64_t>(tolerance_mm);
    const bool started = below ? start_leg(top_mm(floors), Direction::Up)
                               : start_leg(bottom_mm(floors), Direction::Down);
    if (started) phase_ = below ? Phase::Up : Phase::Down;
    return started;
  }

  /// One cycle's sample after the travel's step: the car at `position_mm` moving `direction`,
  /// `zone` the level zone signal. Once as many zones as `floor_count` are passed and the car is
  /// out of the last one, `end_at(target_mm)` ends the leg kLearnRunOutMm further on (true: it
  /// will).
  template <typename EndAt>
  void sample(std::optional<std::int64_t> position_mm, bool zone, Direction direction,
              std::size_t floor_count, EndAt&& end_at) noexcept {
    if (phase_ != Phase::Up || !position_mm) return;
    learner_.sample(*position_mm, zone, direction);
    // Every floor's zone passed: end the leg just beyond the last one (the top terminal).
    if (!run_out_ && learner_.zones_seen() == floor_count && !learner_.in_zone() &&
        end_at(*position_mm + kLearnRunOutMm)) {
      run_out_ = true;
    }
  }

  /// The running leg ended: finished, or `aborted` with `cause` (an abort without a cause is
  /// taken for a stop).
  void leg_ended(bool aborted, Cause cause) noexcept {
    if (!active()) return;
    leg_ended_ = true;
    leg_cause_ = aborted && cause == Cause::None ? Cause::StopRequested : cause;
  }
  /// `stop` or the service stop: the learning ends when its leg has.
  void stop() noexcept {
    if (active()) stopped_ = true;
  }

  /// After each cycle: the next leg or the end. `leg_running` a leg (or its tail) still runs;
  /// `gate()` the refusal (an Answer, nullopt: none) of the leg up after the approach, checked as
  /// a travel's start is; `start_leg` as for begin(). The answer to reply to tag() when the
  /// learning ended now (Ok: record() holds the result), else nullopt.
  template <typename Gate, typename StartLeg>
  std::optional<Answer> step(bool leg_running, const FloorTable& floors, Gate&& gate,
                             StartLeg&& start_leg) noexcept {
    if (phase_ == Phase::Idle) return std::nullopt;
    if (!leg_ended_) {
      // Stopped between the legs: nothing runs that the stop could end.
      if (stopped_ && !leg_running) return end({ReplyCode::NotReady, kLearnStopped});
      return std::nullopt;
    }
    leg_ended_ = false;
    if (stopped_) return end({ReplyCode::NotReady, kLearnStopped});
    if (leg_cause_ != Cause::None) return end({ReplyCode::Fault, to_string(leg_cause_)});
    if (phase_ == Phase::Down) {
      if (const std::optional<Answer> refusal = gate()) return end(*refusal);
      if (!start_leg(top_mm(floors), Direction::Up)) {
        return end({ReplyCode::NotReady, kLearnNotTaken});
      }
      phase_ = Phase::Up;
      return std::nullopt;
    }
    record_.tag = tag_;
    record_.judgement = learner_.judge(floors.size());
    record_.zones_seen = learner_.zones_seen();
    record_.zone_count = learner_.zone_count();
    for (std::size_t i = 0; i < record_.zone_count; ++i) record_.zones[i] = learner_.zone(i);
    return end({ReplyCode::Ok, {}});
  }

 private:
  Answer end(Answer answer) noexcept {
    phase_ = Phase::Idle;
    stopped_ = false;
    return answer;
  }

  Phase phase_ = Phase::Idle;
  std::uint32_t tag_ = 0;
  bool leg_ended_ = false;
  Cause leg_cause_ = Cause::None;  ///< why the leg ended early (None: finished)
  bool stopped_ = false;           ///< `stop` or the service stop asked for it
  bool run_out_ = false;           ///< the end after the last zone is set
  LevelLearner learner_;
  LearnRecord record_;
};

}  // namespace liftd::lift
