#include "dcp/travel/types.hpp"

namespace liftd::travel {

namespace {
void put(ChannelText& text, char c) noexcept {
  if (text.size < text.chars.size()) text.chars[text.size++] = c;
}
// Writes `value` as `digits` ASCII decimal digits (the spec's "BCD" text fields), clamped to the
// largest value that fits.
void put_digits(ChannelText& text, std::uint64_t value, int digits) noexcept {
  std::uint64_t limit = 1;
  for (int i = 0; i < digits; ++i) limit *= 10;
  if (value >= limit) value = limit - 1;
  std::uint64_t divisor = limit / 10;
  for (int i = 0; i < digits; ++i) {
    put(text, static_cast<char>('0' + static_cast<int>((value / divisor) % 10)));
    divisor /= 10;
  }
}
}  // namespace

ChannelText ChannelRequest::body() const noexcept {
  ChannelText text;
  put(text, 'I');
  switch (kind) {
    case Kind::StartParameters:
      // DCP 11.1.2.1: Vmax '1' = V3, '2' = V4; Ss 5 digits in cm.
      put(text, '7');
      put(text, vmax == dcp::Speed::V3 ? '1' : '2');
      put_digits(text, desired_distance_cm, 5);
      break;
    case Kind::Load:
      // DCP 5.12.8: load in percent of rated load, 3 digits.
      put(text, '8');
      put_digits(text, load_percent, 3);
      break;
    case Kind::Position:
      // DCP 5.12.9: sign ('+', '-', 'E' invalid) and 6 digits, mm from the lowest level.
      put(text, '9');
      if (!position_mm) {
        put(text, 'E');
        put_digits(text, 0, 6);
      } else {
        put(text, *position_mm < 0 ? '-' : '+');
        const std::int64_t magnitude = *position_mm < 0 ? -*position_mm : *position_mm;
        put_digits(text, static_cast<std::uint64_t>(magnitude), 6);
      }
      break;
  }
  return text;
}

std::optional<std::string_view> validate(const TravelConfig& config) noexcept {
  if (!dcp::data_info_type_from_char(static_cast<char>(config.data_info_type))) {
    return "data_info_type";
  }
  if (config.speed_message_cycles == 0) return "speed_message_cycles";
  if (config.i7_timeout_ms == 0) return "i7_timeout_ms";
  if (config.i8_timeout_ms == 0) return "i8_timeout_ms";
  if (config.start_timeout_ms == 0) return "start_timeout_ms";
  if (config.stop_timeout_ms == 0) return "stop_timeout_ms";
  if (config.fast_start_timeout_ms == 0) return "fast_start_timeout_ms";
  if (config.crawl_timeout_ms == 0) return "crawl_timeout_ms";
  if (config.relevel_threshold_mm <= config.level_tolerance_mm) return "relevel_threshold_mm";
  if (config.arrival_tolerance_mm < config.level_tolerance_mm) return "arrival_tolerance_mm";
  if (config.relevel_zone_mm <= config.relevel_threshold_mm) return "relevel_zone_mm";
  // The lead stands for the drive's stopping distance from crawl (a few mm at V0 = 0.05 m/s);
  // beyond 100 mm B2 would drop before the car is anywhere near the level.
  if (config.dcp3_stop_lead_mm > 100) return "dcp3_stop_lead_mm";
  // DCP 3.5.3.7: installations have 1 to 7 travelling speeds.
  if (config.dcp3_speed_count < 1 || config.dcp3_speed_count > 7) return "dcp3_speed_count";
  return std::nullopt;
}

std::size_t speed_index(dcp::Speed speed) noexcept {
  const auto word = dcp::speed_word(speed);
  // DCP 3.5.3.7: exactly one of the eleven bits G0..G10 is set in a speed word.
  std::size_t index = 0;
  while (index < dcp::kAllSpeeds.size() && (word >> index) != 1U) ++index;
  return index < dcp::kAllSpeeds.size() ? index : 0;
}

int speed_number(dcp::Speed speed) noexcept {
  switch (speed) {
    case dcp::Speed::V1:
      return 1;
    case dcp::Speed::V2:
      return 2;
    case dcp::Speed::V3:
      return 3;
    case dcp::Speed::V4:
      return 4;
    case dcp::Speed::V5:
      return 5;
    case dcp::Speed::V6:
      return 6;
    case dcp::Speed::V7:
      return 7;
    default:
      return 0;
  }
}

std::string_view to_string(TravelKind kind) noexcept {
  switch (kind) {
    case TravelKind::None:
      return "none";
    case TravelKind::Dcp4Distance:
      return "distance";
    case TravelKind::Dcp4Relevel:
      return "relevel_distance";
    case TravelKind::Dcp3Speed:
      return "speed";
    case TravelKind::Dcp3Crawl:
      return "crawl";
    case TravelKind::Inspection:
      return "inspection";
    case TravelKind::Recall:
      return "recall";
    case TravelKind::Relevel:
      return "relevel";
  }
  return "none";
}

std::string_view to_string(Event::Type type) noexcept {
  switch (type) {
    case Event::Type::Started:
      return "started";
    case Event::Type::Finished:
      return "finished";
    case Event::Type::Aborted:
      return "aborted";
    case Event::Type::TargetExtended:
      return "target_extended";
    case Event::Type::TargetRefused:
      return "target_refused";
    case Event::Type::FastStartArmed:
      return "fast_start_armed";
    case Event::Type::DriveFault:
      return "drive_fault";
    case Event::Type::DriveFaultCleared:
      return "drive_fault_cleared";
  }
  return "started";
}

std::string_view to_string(StartResult result) noexcept {
  switch (result) {
    case StartResult::Accepted:
      return "accepted";
    case StartResult::Busy:
      return "a travel is running or the drive still reports S1";
    case StartResult::WrongProtocol:
      return "travel type not available with this drive's DCP type";
    case StartResult::BadSpeed:
      return "speed not allowed for this travel or installation";
    case StartResult::NoPosition:
      return "no valid car position";
    case StartResult::AlreadyThere:
      return "the car is already at that level";
    case StartResult::NoDirection:
      return "direction unknown";
    case StartResult::InspectionMode:
      return "inspection or recall is switched on";
    case StartResult::ShuttingDown:
      return "the service is stopping";
  }
  return "accepted";
}

std::string_view to_string(ExtendResult result) noexcept {
  switch (result) {
    case ExtendResult::Accepted:
      return "accepted";
    case ExtendResult::Pending:
      return "sent to the drive, waiting for its acceptance (S5)";
    case ExtendResult::Busy:
      return "an earlier target change still waits for the drive's acceptance (S5)";
    case ExtendResult::NoDistanceTravel:
      return "no DCP4 distance travel running";
    case ExtendResult::NotFurther:
      return "a running travel can only be extended further in its direction";
    case ExtendResult::AdvanceWarning:
      return "advance warning (S2) set: no extension (DCP 9.1.5)";
    case ExtendResult::DecelUnknown:
      return "deceleration distance unknown";
    case ExtendResult::TooLate:
      return "too late: the car can no longer stop beyond its current target";
  }
  return "accepted";
}

}  // namespace liftd::travel
