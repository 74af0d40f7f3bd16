// One sample of a travel's curve, taken on the real-time thread once per step while a run is
// in progress (every drive kind alike), and the sampler that makes them: the car's position, its
// speed, the remaining distance where the drive link carries one, and the drive's command and
// status bits as integers (the kind's folder names the bits). The io thread assembles the samples
// into travels (host/travel_log.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/mono_time.hpp"

namespace liftd::lift {

/// A fixed-size plain sample: copied into the lock-free queue, never allocates.
struct TravelSample {
  MonoTime at{};
  std::uint32_t run = 0;          ///< counts the runs the sampler saw; a new value starts a travel
  std::string_view kind;          ///< the run's kind as the API names it (a static string)
  std::int64_t position_mm = 0;   ///< valid when position_known
  std::int64_t remaining_mm = 0;  ///< valid when remaining_known
  std::int32_t speed_mm_s = 0;    ///< valid when speed_known; + up, - down
  std::uint32_t command_bits = 0;
  std::uint32_t status_bits = 0;
  std::int32_t target_floor = -1;  ///< -1: none
  bool position_known = false;
  bool speed_known = false;
  bool remaining_known = false;
  bool last = false;  ///< the first step at rest after the run: the run's last sample
};

/// What the kind reads of its drive link in a step.
struct DriveBits {
  std::uint32_t command = 0;                 ///< the command bits sent this step
  std::uint32_t status = 0;                  ///< the drive's last status bits
  std::optional<std::int64_t> remaining_mm;  ///< the remaining distance the link carries
};

/// Makes the samples of the runs, one per step while a run is in progress and one more at the
/// first step after it. The speed is the position's change over at least kSpeedWindow (the
/// encoder counts whole millimetres: over one 15 ms DCP cycle 1 mm is 67 mm/s).
class TravelSampler {
 public:
  static constexpr MonoTime kSpeedWindow = std::chrono::milliseconds(45);

  /// One step: `running` while a run is in progress, `kind` its API name. Returns the sample to
  /// queue, if any.
  std::optional<TravelSample> step(MonoTime now, bool running, std::string_view kind,
                                   std::optional<std::int64_t> position_mm,
                                   std::optional<std::size_t> target_floor,
                                   const DriveBits& bits) noexcept {
    remember(now, position_mm);
    if (!running && !in_run_) return std::nullopt;
    if (running && !in_run_) {
      in_run_ = true;
      ++run_;
    }
    if (running) kind_ = kind;
    TravelSample s;
    s.at = now;
    s.run = run_;
    s.kind = kind_;
    s.position_known = position_mm.has_value();
    s.position_mm = position_mm.value_or(0);
    if (const auto speed = speed_mm_s(now)) {
      s.speed_known = true;
      s.speed_mm_s = *speed;
    }
    s.remaining_known = bits.remaining_mm.has_value();
    s.remaining_mm = bits.remaining_mm.value_or(0);
    s.command_bits = bits.command;
    s.status_bits = bits.status;
    if (target_floor) target_floor_ = static_cast<std::int32_t>(*target_floor);
    s.target_floor = target_floor_;
    s.last = !running;
    if (!running) {
      in_run_ = false;
      target_floor_ = -1;
    }
    return s;
  }

 private:
  struct Fix {
    MonoTime at{};
    std::int64_t position_mm = 0;
    bool known = false;
  };
  static constexpr std::size_t kFixes = 32;

  void remember(MonoTime now, std::optional<std::int64_t> position_mm) noexcept {
    next_ = (next_ + 1) % kFixes;
    fixes_[next_] = Fix{now, position_mm.value_or(0), position_mm.has_value()};
  }
  /// The newest fix at least kSpeedWindow older than the newest one, else the oldest there is.
  std::optional<std::int32_t> speed_mm_s(MonoTime now) const noexcept {
    const Fix& newest = fixes_[next_];
    if (!newest.known) return std::nullopt;
    const Fix* base = nullptr;
    for (std::size_t back = 1; back < kFixes; ++back) {
      const Fix& f = fixes_[(next_ + kFixes - back) % kFixes];
      if (!f.known || f.at >= now) break;
      base = &f;
      if (now - f.at >= kSpeedWindow) break;
    }
    if (base == nullptr) return std::nullopt;
    const auto dt_us =
        std::chrono::duration_cast<std::chrono::microseconds>(now - base->at).count();
    if (dt_us <= 0) return std::nullopt;
    return static_cast<std::int32_t>((newest.position_mm - base->position_mm) * 1'000'000 / dt_us);
  }

  std::array<Fix, kFixes> fixes_{};
  std::size_t next_ = 0;
  std::uint32_t run_ = 0;
  bool in_run_ = false;
  std::string_view kind_;
  std::int32_t target_floor_ = -1;
};

}  // namespace liftd::lift
