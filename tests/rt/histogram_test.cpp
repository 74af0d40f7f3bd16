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

TEST(RtHistogram, PercentilesBeyondTheRangePrintAsMoreThanTheRange) {
  // Legend: 0..100 us in 10 us bins; 90 samples of 5 us and 10 of 5 ms. p50 and p90 lie in
  // range, p95 and p99 among the 5 ms samples: the bins cannot tell their value, only "> 100".
  Histogram<10> h(microseconds(10));
  for (int i = 0; i < 90; ++i) h.record(microseconds(5));
  for (int i = 0; i < 10; ++i) h.record(microseconds(5000));
  const HistogramData d = h.copy();
  struct Case {
    double fraction;
    bool beyond;
    const char* text;
  };
  const Case cases[] = {
      {0.5, false, "10.0"}, {0.9, false, "10.0"}, {0.95, true, "> 100"}, {0.99, true, "> 100"}};
  for (const auto& c : cases) {
    EXPECT_EQ(d.beyond_range(c.fraction), c.beyond) << c.fraction;
    EXPECT_EQ(d.percentile_text(c.fraction), c.text) << c.fraction;
  }
  EXPECT_DOUBLE_EQ(d.range_us(), 100.0);
}

TEST(RtHistogram, LastBinWithinTheRangeIsNotBeyondIt) {
  Histogram<10> h(microseconds(10));  // covers 0..100 us
  h.record(microseconds(95));         // in the last bin, but inside the range
  const HistogramData d = h.copy();
  EXPECT_FALSE(d.beyond_range(1.0));
  EXPECT_EQ(d.percentile_text(1.0), "95.0");
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
