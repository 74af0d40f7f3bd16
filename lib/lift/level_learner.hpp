// The learning travel's recorder: fed one sample per cycle while the car travels up through the
// whole shaft at the learning speed, it records where each level zone signal starts and ends,
// gives each floor's level (the middle of its zone) and zone length, and judges the result.
// Pure and fixed-size: it runs inside the real-time cycle of every drive kind (no allocation,
// lock, log or exception).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "lift/floors.hpp"
#include "lift/inputs.hpp"

namespace liftd::lift {

/// A level zone shorter than this is implausible: a car stopped inside it within the level
/// tolerance (travel.level_tolerance_mm, 5 mm by default) and relevelled from the relevelling
/// threshold (15 mm) must find the zone on both sides of the level, so it spans at least twice
/// the threshold; a shorter one is a vane seen edge-on or a bouncing contact.
inline constexpr std::int64_t kMinLevelZoneMm = 30;
/// A level zone longer than this is implausible: the unlocking zone of a landing door, which
/// the level zone marks, extends at most 0.20 m above and below the landing (EN 81-20 5.3.8.1).
inline constexpr std::int64_t kMaxLevelZoneMm = 400;
/// An input change counts once it holds for this many samples in a row: a contact that
/// bounces for one cycle at a zone's edge is not a zone.
inline constexpr int kLevelZoneStableSamples = 2;

/// One level zone as the car crossed it travelling up (mm from the lowest level). Each edge is
/// the middle between the last sample before the input changed and the first after it.
struct LearnedZone {
  std::int64_t start_mm = 0;
  std::int64_t end_mm = 0;
  /// The floor's level: the middle of its zone.
  std::int64_t level_mm() const noexcept { return start_mm + (end_mm - start_mm) / 2; }
  std::int64_t length_mm() const noexcept { return end_mm - start_mm; }
  bool operator==(const LearnedZone&) const = default;
};

/// How a learning travel's record was judged.
enum class LearnVerdict : std::uint8_t {
  Ok,                ///< one plausible zone per floor
  BeganInZone,       ///< the first sample was inside a zone: its start was not seen
  EndedInZone,       ///< the last sample was inside a zone: its end was not seen
  ZoneCountDiffers,  ///< zones found != floors configured
  ZoneTooShort,      ///< a zone shorter than kMinLevelZoneMm
  ZoneTooLong,       ///< a zone longer than kMaxLevelZoneMm
};
/// "ok", "began_in_zone", ... for the API and the journal.
std::string_view to_string(LearnVerdict verdict) noexcept;

/// The verdict and, for a zone judged implausible, which zone (0 = lowest).
struct LearnJudgement {
  LearnVerdict verdict = LearnVerdict::Ok;
  std::size_t zone = 0;
  bool ok() const noexcept { return verdict == LearnVerdict::Ok; }
};

/// Records level zones from samples taken travelling up.
class LevelLearner {
 public:
  /// Forgets everything: a new learning travel.
  void reset() noexcept { *this = LevelLearner{}; }
  /// One cycle's sample. Only samples taken travelling up count (the approach to the bottom
  /// records nothing).
  void sample(std::int64_t position_mm, bool level_zone, Direction direction) noexcept;

  /// Zones completed so far (at most kMaxFloors; more are counted in zones_seen()).
  std::size_t zone_count() const noexcept { return count_ < kMaxFloors ? count_ : kMaxFloors; }
  /// Every zone completed, including those beyond kMaxFloors.
  std::size_t zones_seen() const noexcept { return count_; }
  /// Zone `index` (< zone_count()).
  const LearnedZone& zone(std::size_t index) const noexcept { return zones_[index]; }
  /// The car is inside a zone now (as debounced).
  bool in_zone() const noexcept { return inside_; }

  /// The record against `floor_count` floors and the plausible zone lengths.
  LearnJudgement judge(std::size_t floor_count, std::int64_t min_zone_mm = kMinLevelZoneMm,
                       std::int64_t max_zone_mm = kMaxLevelZoneMm) const noexcept;

 private:
  std::array<LearnedZone, kMaxFloors> zones_{};
  std::size_t count_ = 0;
  bool started_ = false;  // a first sample travelling up was taken
  bool began_in_zone_ = false;
  bool inside_ = false;               // debounced input
  bool skip_next_close_ = false;      // the zone the car began in ends without a start
  std::int64_t last_mm_ = 0;          // the previous sample's position
  int pending_ = 0;                   // samples in a row that differ from `inside_`
  std::int64_t pending_edge_mm_ = 0;  // where the pending change began
  std::int64_t open_start_mm_ = 0;    // the open zone's start
};

}  // namespace liftd::lift
