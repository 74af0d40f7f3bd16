#include "record/time_text.hpp"

#include <chrono>
#include <cstdio>

namespace liftd::record {

namespace {

struct Civil {
  int year;
  unsigned month, day, hour, minute, second, ms;
};

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

Civil civil(std::int64_t unix_ms) {
  using namespace std::chrono;
  const std::int64_t day = floor_div(unix_ms, kMsPerDay);
  const std::int64_t in_day = unix_ms - day * kMsPerDay;
  const year_month_day ymd{sys_days{days{day}}};
  return Civil{static_cast<int>(ymd.year()),
               static_cast<unsigned>(ymd.month()),
               static_cast<unsigned>(ymd.day()),
               static_cast<unsigned>(in_day / 3'600'000),
               static_cast<unsigned>(in_day / 60'000 % 60),
               static_cast<unsigned>(in_day / 1000 % 60),
               static_cast<unsigned>(in_day % 1000)};
}

}  // namespace

std::string format_utc_ms(std::int64_t unix_ms) {
  const Civil c = civil(unix_ms);
  char text[40];
  std::snprintf(text, sizeof text, "%04d-%02u-%02uT%02u:%02u:%02u.%03uZ", c.year, c.month, c.day,
                c.hour, c.minute, c.second, c.ms);
  return text;
}

std::string format_utc_compact(std::int64_t unix_ms) {
  const Civil c = civil(unix_ms);
  char text[40];
  std::snprintf(text, sizeof text, "%04d%02u%02uT%02u%02u%02uZ", c.year, c.month, c.day, c.hour,
                c.minute, c.second);
  return text;
}

std::int64_t utc_day(std::int64_t unix_ms) {
  return floor_div(unix_ms, kMsPerDay);
}

std::string format_day(std::int64_t day) {
  const Civil c = civil(day * kMsPerDay);
  char text[24];
  std::snprintf(text, sizeof text, "%04d-%02u-%02u", c.year, c.month, c.day);
  return text;
}

}  // namespace liftd::record
