#include "lift/level_learner.hpp"

namespace liftd::lift {

std::string_view to_string(LearnVerdict verdict) noexcept {
  switch (verdict) {
    case LearnVerdict::Ok:
      return "ok";
    case LearnVerdict::BeganInZone:
      return "began_in_zone";
    case LearnVerdict::EndedInZone:
      return "ended_in_zone";
    case LearnVerdict::ZoneCountDiffers:
      return "zone_count_differs";
    case LearnVerdict::ZoneTooShort:
      return "zone_too_short";
    case LearnVerdict::ZoneTooLong:
      return "zone_too_long";
  }
  return "?";
}

void LevelLearner::sample(std::int64_t position_mm, bool level_zone, Direction direction) noexcept {
  if (direction != Direction::Up) return;
  if (!started_) {
    started_ = true;
    inside_ = level_zone;
    began_in_zone_ = level_zone;
    skip_next_close_ = level_zone;
    last_mm_ = position_mm;
    return;
  }
  if (level_zone == inside_) {
    pending_ = 0;
  } else {
    // The edge lies between the last sample that showed the old value and this one.
    if (pending_ == 0) {
      pending_edge_mm_ = last_mm_ + (position_mm - last_mm_) / 2;
    }
    if (++pending_ >= kLevelZoneStableSamples) {
      pending_ = 0;
      inside_ = level_zone;
      if (inside_) {
        open_start_mm_ = pending_edge_mm_;
      } else if (skip_next_close_) {
        skip_next_close_ = false;  // the zone the car began in: its start is unknown
      } else {
        if (count_ < kMaxFloors) zones_[count_] = {open_start_mm_, pending_edge_mm_};
        ++count_;
      }
    }
  }
  last_mm_ = position_mm;
}

LearnJudgement LevelLearner::judge(std::size_t floor_count, std::int64_t min_zone_mm,
                                   std::int64_t max_zone_mm) const noexcept {
  if (began_in_zone_) return {LearnVerdict::BeganInZone, 0};
  if (inside_) return {LearnVerdict::EndedInZone, zone_count()};
  if (count_ != floor_count) return {LearnVerdict::ZoneCountDiffers, 0};
  for (std::size_t i = 0; i < zone_count(); ++i) {
    if (zones_[i].length_mm() < min_zone_mm) return {LearnVerdict::ZoneTooShort, i};
    if (zones_[i].length_mm() > max_zone_mm) return {LearnVerdict::ZoneTooLong, i};
  }
  return {};
}

}  // namespace liftd::lift
