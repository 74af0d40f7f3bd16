#include "api/request_budget.hpp"

#include <algorithm>
#include <cmath>

namespace liftd::api {

// In whole clock ticks (no rounding drift): one request is due every `interval_`; `due_` is when
// the budget would be back to full after what was taken, and a request may be taken while
// `due_` lies at most `tolerance_` (the burst less one request) ahead of now.

RequestBudget::RequestBudget(double per_second, std::size_t min_burst, Clock::time_point now)
    : min_burst_(std::max<std::size_t>(1, min_burst)), due_(now) {
  set_rate(per_second, now);
}

void RequestBudget::set_rate(double per_second, Clock::time_point now) {
  per_second_ = per_second > 0 ? per_second : 0;
  if (per_second_ <= 0) {
    interval_ = Clock::duration::zero();
    tolerance_ = Clock::duration::zero();
    due_ = now;
    return;
  }
  interval_ = std::max(Clock::duration(1), std::chrono::round<Clock::duration>(
                                               std::chrono::duration<double>(1.0 / per_second_)));
  const auto burst = std::max(static_cast<double>(min_burst_), std::floor(per_second_ / 10.0));
  tolerance_ = interval_ * (static_cast<std::int64_t>(burst) - 1);
  // What was saved stays, up to the new burst; what was taken is owed at the new rate.
  due_ = std::clamp(due_, now, now + tolerance_ + interval_);
}

bool RequestBudget::take(Clock::time_point now) {
  if (per_second_ <= 0) return true;
  const Clock::time_point from = std::max(due_, now);
  if (from - now > tolerance_) return false;
  due_ = from + interval_;
  return true;
}

RequestBudget::Clock::time_point RequestBudget::next_at(Clock::time_point now) const {
  if (per_second_ <= 0) return now;
  return std::max(now, due_ - tolerance_);
}

}  // namespace liftd::api
