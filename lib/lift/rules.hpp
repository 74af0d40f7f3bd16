// The lift rules every controller applies alike, whatever drive it runs (the DCP lift's
// DcpController and the ControllerCore of the SCH001 and USS lifts each own one): the machine's
// inputs as the provider last sent them, the API's software inspection with its held direction,
// the start grace, and the answers to the calls commands. One copy, so a dispatcher and a
// technician see the same lift on every drive kind (docs/api.md `inputs`, `inspection`, `calls`).
//
// Real-time safe: no allocation, no lock, no exception; the answers are static strings.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "common/mono_time.hpp"
#include "lift/inputs.hpp"
#include "lift/lift_model.hpp"

namespace liftd::lift {

/// How a command ended, as the API's error codes name it.
enum class ReplyCode : std::uint8_t {
  Ok,
  NotReady,    ///< a condition forbids it now (the detail names it)
  Busy,        ///< something else is running
  BadRequest,  ///< the request cannot apply to this lift (the detail says why)
  Fault,       ///< the drive or its link is in fault
  Timeout,     ///< the drive did not answer a request in time
};

/// A command's answer: its code and a static text ("" for a plain ok).
struct Answer {
  ReplyCode code = ReplyCode::Ok;
  std::string_view detail;
};

/// docs/api.md `calls` cancel of the floor a travel runs to: its answers.
inline constexpr std::string_view kTooLateToCancel =
    "the car can no longer stop before the floor it travels to";
inline constexpr std::string_view kCancelStopsAt = "the car stops at the next floor it can";
inline constexpr std::string_view kCancelStopsNow = "the travel ended before the car moved";

class LiftRules {
 public:
  /// `inputs_timeout`: inputs older than this count as lost (config inputs.timeout_ms).
  /// `inspection_hold`: an API inspection direction must be repeated within this (config
  /// travel.inspection_hold_ms).
  LiftRules(MonoTime inputs_timeout, MonoTime inspection_hold) noexcept
      : inputs_timeout_(inputs_timeout), inspection_hold_(inspection_hold) {}

  /// The controller started at `now`: the start grace counts from here.
  void start(MonoTime now) noexcept { start_at_ = now; }
  /// After start, the link, the inputs and the position get two input timeouts to arrive before
  /// they count as lost.
  bool start_grace_over(MonoTime now) const noexcept {
    return now - start_at_ > inputs_timeout_ * 2;
  }

  /// The provider's complete inputs, received at `now`.
  void take_inputs(const Inputs& inputs, MonoTime now) noexcept {
    provider_inputs_ = inputs;
    inputs_at_ = now;
    inputs_seen_ = true;
  }
  /// The API's software inspection: on/off and the direction held until `now` +
  /// inspection_hold (a client repeats it to keep the car moving).
  void take_inspection(bool on, Direction direction, MonoTime now) noexcept {
    api_inspection_ = on;
    api_direction_ = on ? direction : Direction::None;
    api_hold_until_ = now + inspection_hold_;
  }
  /// The provider's last inputs (valid while fresh) with the API's inspection and its buttons
  /// while the direction is held.
  Inputs current_inputs(MonoTime now) const noexcept;

  /// `calls` add, cancel, insert or set on `lift`. While the service stops no call is added
  /// (the calls were cleared and no travel starts); `add` of a floor already queued is ok.
  /// `heading_for`: the queue's first floor is the one a travel runs to now; `set` and `insert`
  /// keep it first (a running travel is not re-targeted by the queue).
  static Answer answer_call(LiftModel& lift, const CallCommand& call, bool shutting_down,
                            bool heading_for) noexcept;

 private:
  MonoTime inputs_timeout_;
  MonoTime inspection_hold_;
  MonoTime start_at_{};
  Inputs provider_inputs_{};
  MonoTime inputs_at_{};
  bool inputs_seen_ = false;
  bool api_inspection_ = false;
  Direction api_direction_ = Direction::None;
  MonoTime api_hold_until_{};
};

}  // namespace liftd::lift
