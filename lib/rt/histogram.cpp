#include "rt/histogram.hpp"

#include <algorithm>
#include <cmath>

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

double HistogramData::mean_us() const noexcept {
  if (count == 0) return 0.0;
  return static_cast<double>(sum_ns) / static_cast<double>(count) / 1000.0;
}

}  // namespace liftd::rt
