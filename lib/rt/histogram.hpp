// Fixed-size timing histograms in the style of cyclictest: one writer (the cycle thread)
// records durations into preallocated bins; any thread may take a copy and ask percentiles.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace liftd::rt {

/// A copy of a histogram, taken outside the real-time thread; answers percentile queries.
struct HistogramData {
  std::int64_t bin_width_ns = 0;    ///< width of every bin
  std::vector<std::uint64_t> bins;  ///< counts; the last bin also holds everything beyond it
  std::uint64_t count = 0;          ///< samples recorded
  std::int64_t sum_ns = 0;          ///< sum of the samples (negative ones count as 0)
  std::int64_t max_ns = 0;          ///< largest sample

  /// The value at or below which `fraction` (0..1) of the samples lie, in microseconds; the
  /// upper edge of the bin that crosses the fraction, but never above the maximum. 0 if empty.
  double percentile_us(double fraction) const noexcept;
  /// True if the `fraction` percentile lies in the last bin, i.e. at or beyond the range the
  /// bins cover: its true value is only known to be >= range_us().
  bool beyond_range(double fraction) const noexcept;
  /// The range the bins cover (bins * width) in microseconds.
  double range_us() const noexcept {
    return static_cast<double>(bin_width_ns) * static_cast<double>(bins.size()) / 1000.0;
  }
  /// percentile_us() as text with one decimal, or "> R" (R = range_us()) when beyond_range():
  /// a figure a benchmark can print without claiming a value the bins cannot tell.
  std::string percentile_text(double fraction) const;
  /// Mean of the samples in microseconds (0 if empty).
  double mean_us() const noexcept;
  /// Largest sample in microseconds.
  double max_us() const noexcept { return static_cast<double>(max_ns) / 1000.0; }
};

/// `Bins` bins of a width given at construction. record() is wait-free and allocation free;
/// it must only be called from one thread at a time. copy() may run on any thread.
template <std::size_t Bins>
class Histogram {
  static_assert(Bins >= 2);

 public:
  /// Bins of `bin_width` each; the range covered is Bins * bin_width.
  explicit Histogram(std::chrono::nanoseconds bin_width) noexcept
      : bin_width_ns_(bin_width.count() > 0 ? bin_width.count() : 1) {}

  /// Writer: adds one sample (negative samples land in bin 0).
  void record(std::chrono::nanoseconds sample) noexcept {
    const std::int64_t ns = sample.count() > 0 ? sample.count() : 0;
    std::size_t bin = static_cast<std::size_t>(ns / bin_width_ns_);
    if (bin >= Bins) bin = Bins - 1;
    bump(bins_[bin], 1);
    bump(count_, 1);
    sum_ns_.store(sum_ns_.load(std::memory_order_relaxed) + ns, std::memory_order_relaxed);
    if (ns > max_ns_.load(std::memory_order_relaxed)) {
      max_ns_.store(ns, std::memory_order_relaxed);
    }
  }

  /// Writer: forgets every sample.
  void reset() noexcept {
    for (auto& b : bins_) b.store(0, std::memory_order_relaxed);
    count_.store(0, std::memory_order_relaxed);
    sum_ns_.store(0, std::memory_order_relaxed);
    max_ns_.store(0, std::memory_order_relaxed);
  }

  /// Any thread: a copy of the bins. Samples recorded during the copy may be half in it.
  HistogramData copy() const {
    HistogramData d;
    d.bin_width_ns = bin_width_ns_;
    d.bins.resize(Bins);
    for (std::size_t i = 0; i < Bins; ++i) d.bins[i] = bins_[i].load(std::memory_order_relaxed);
    d.count = count_.load(std::memory_order_relaxed);
    d.sum_ns = sum_ns_.load(std::memory_order_relaxed);
    d.max_ns = max_ns_.load(std::memory_order_relaxed);
    return d;
  }

 private:
  static void bump(std::atomic<std::uint64_t>& a, std::uint64_t by) noexcept {
    // Single writer: a plain load and store is enough and cheaper than fetch_add.
    a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
  }

  std::int64_t bin_width_ns_;
  std::array<std::atomic<std::uint64_t>, Bins> bins_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> sum_ns_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

}  // namespace liftd::rt
