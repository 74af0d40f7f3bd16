// Histogram: binning, overflow and percentile answers on known data.
#include "rt/histogram.hpp"

#include <gtest/gtest.h>

namespace liftd::rt {
namespace {

using std::chrono::microseconds;

TEST(RtHistogram, EmptyAnswersZero) {
  Histogram<10> h(microseconds(1));
  const HistogramData d = h.copy();
  EXPECT_EQ(d.count, 0U);
  EXPECT_EQ(d.percentile_us(0.5), 0.0);
  EXPECT_EQ(d.mean_us(), 0.0);
}

TEST(RtHistogram, PercentilesAreBinUpperEdgesCappedAtMax) {
  // Legend: 100 samples of 0..99 us in 1 us bins. The p-th percentile is the upper edge of the
  // bin holding the ceil(p * 100)-th smallest sample.
  Histogram<1000> h(microseconds(1));
  for (int us = 0; us < 100; ++us) h.record(microseconds(us));
  const HistogramData d = h.copy();
  struct Case {
    double fraction;
    double expected_us;
  };
  const Case cases[] = {{0.0, 1.0}, {0.01, 1.0}, {0.5, 50.0}, {0.99, 99.0}, {1.0, 99.0}};
  for (const auto& c : cases)
    EXPECT_DOUBLE_EQ(d.percentile_us(c.fraction), c.expected_us) << c.fraction;
  EXPECT_EQ(d.count, 100U);
  EXPECT_DOUBLE_EQ(d.mean_us(), 49.5);
  EXPECT_DOUBLE_EQ(d.max_us(), 99.0);
}

TEST(RtHistogram, OverflowLandsInLastBinAndMaxStaysExact) {
  Histogram<10> h(microseconds(10));  // covers 0..100 us
  h.record(microseconds(5));
  h.record(microseconds(5000));  // beyond the range
  const HistogramData d = h.copy();
  EXPECT_EQ(d.bins[0], 1U);
  EXPECT_EQ(d.bins[9], 1U);
  EXPECT_DOUBLE_EQ(d.percentile_us(1.0), 100.0);  // upper edge of the last bin
  EXPECT_DOUBLE_EQ(d.max_us(), 5000.0);
}

TEST(RtHistogram, NegativeSamplesCountAsZero) {
  Histogram<4> h(microseconds(1));
  h.record(microseconds(-30));
  const HistogramData d = h.copy();
  EXPECT_EQ(d.bins[0], 1U);
  EXPECT_EQ(d.sum_ns, 0);
}

TEST(RtHistogram, ResetForgetsEverything) {
  Histogram<4> h(microseconds(1));
  h.record(microseconds(2));
  h.reset();
  EXPECT_EQ(h.copy().count, 0U);
  EXPECT_EQ(h.copy().max_ns, 0);
}

}  // namespace
}  // namespace liftd::rt
