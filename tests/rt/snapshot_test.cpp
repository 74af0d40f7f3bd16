// Snapshot (triple buffer): newest value wins, no torn reads across threads.
#include "common/snapshot_box.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <thread>

namespace liftd::rt {
namespace {

struct State {
  std::uint64_t version = 0;
  std::array<std::uint64_t, 8> copies{};  // every element equals version when not torn
};

State make_state(std::uint64_t v) {
  State s;
  s.version = v;
  s.copies.fill(v);
  return s;
}

TEST(RtSnapshot, ReadsDefaultBeforeFirstPublish) {
  SnapshotBox<State> box;
  State out = make_state(7);
  EXPECT_FALSE(box.read(out));
  EXPECT_EQ(out.version, 0U);
}

TEST(RtSnapshot, ReturnsNewestPublishAndReportsFreshnessOnce) {
  SnapshotBox<State> box;
  box.publish(make_state(1));
  box.publish(make_state(2));
  box.publish(make_state(3));
  State out;
  EXPECT_TRUE(box.read(out));
  EXPECT_EQ(out.version, 3U);
  EXPECT_FALSE(box.read(out));  // nothing new: same value, not fresh
  EXPECT_EQ(out.version, 3U);
  box.publish(make_state(4));
  EXPECT_TRUE(box.read(out));
  EXPECT_EQ(out.version, 4U);
}

TEST(RtSnapshot, TwoThreadsNeverSeeTornOrOlderValues) {
  constexpr std::uint64_t kVersions = 100000;
  SnapshotBox<State> box;
  std::thread writer([&box] {
    for (std::uint64_t v = 1; v <= kVersions; ++v) box.publish(make_state(v));
  });
  std::uint64_t last = 0;
  std::uint64_t torn = 0;
  std::uint64_t backwards = 0;
  while (last < kVersions) {
    const State s = box.read();
    for (std::uint64_t c : s.copies) {
      if (c != s.version) ++torn;
    }
    if (s.version < last) ++backwards;
    last = s.version;
  }
  writer.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_EQ(backwards, 0U);
}

}  // namespace
}  // namespace liftd::rt
