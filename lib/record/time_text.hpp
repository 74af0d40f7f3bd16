// Wall-clock times as the record's answers and file names write them (UTC, from ms since the
// Unix epoch), and the UTC day a time falls on.
#pragma once

#include <cstdint>
#include <string>

namespace liftd::record {

inline constexpr std::int64_t kMsPerDay = 86'400'000;

/// "2026-11-28T14:03:07.250Z"
std::string format_utc_ms(std::int64_t unix_ms);
/// "20261128T140307Z" (for a file name: no ':' and no '.')
std::string format_utc_compact(std::int64_t unix_ms);
/// Days since 1970-01-01 (UTC) of the day `unix_ms` falls on (floor, also before 1970).
std::int64_t utc_day(std::int64_t unix_ms);
/// "2026-11-28" for a day number of utc_day.
std::string format_day(std::int64_t day);

}  // namespace liftd::record
