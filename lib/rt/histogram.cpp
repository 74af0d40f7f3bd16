#include "rt/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace liftd::rt {

double HistogramData::percentile_us(double fraction) const noexcept {
  if (count == 0 || bins.empty()) return 0.0;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  // The rank of the sample we look for, 1-based: ceil(fraction * count), at least 1.
  auto rank = static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(count)));
  rank = std::max<std::uint64_t>(rank, 1);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins.size(); ++i) {
    seen += bins[i];
    if (seen >= rank) {
      const std::int64_t upper_ns = static_cast<std::int64_t>(i + 1) * bin_width_ns;
      return static_cast<double>(std::min(upper_ns, max_ns)) / 1000.0;
    }
  }
  return max_us();
}

bool HistogramData::beyond_range(double fraction) const noexcept {
  if (count == 0 || bins.empty()) return false;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  auto rank = static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(count)));
  rank = std::max<std::uint64_t>(rank, 1);
  // Beyond the range when fewer than `rank` samples lie in the bins before the last one, and
  // the largest sample reached the last bin's lower edge.
  std::uint64_t below = 0;
  for (std::size_t i = 0; i + 1 < bins.size(); ++i) below += bins[i];
  const auto last_edge = static_cast<std::int64_t>(bins.size() - 1) * bin_width_ns;
  return below < rank && max_ns >= last_edge + bin_width_ns;
}

std::string HistogramData::percentile_text(double fraction) const {
  char buf[32];
  if (beyond_range(fraction)) {
    std::snprintf(buf, sizeof buf, "> %.0f", range_us());
  } else {
    std::snprintf(buf, sizeof buf, "%.1f", percentile_us(fraction));
  }
  return buf;
}

double HistogramData::mean_us() const noexcept {
  if (count == 0) return 0.0;
  return static_cast<double>(sum_ns) / static_cast<double>(count) / 1000.0;
}

}  // namespace liftd::rt
