// The termios PARMRK decoder: escapes for 0xFF data, marked error characters and breaks, also
// when an escape is split across reads.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "uss/line.hpp"

namespace liftd::uss {
namespace {

std::vector<RxChar> run(ParmrkDecoder& d, std::vector<std::uint8_t> raw) {
  std::vector<RxChar> out(raw.size());
  out.resize(d.decode(raw, out));
  return out;
}

constexpr LineError kOk = LineError::None;

TEST(UssParmrk, Sequences) {
  struct Case {
    std::vector<std::uint8_t> raw;
    std::vector<RxChar> chars;
  };
  for (const Case& c : {
           Case{{0x02, 0x06, 0x01}, {{0x02, kOk}, {0x06, kOk}, {0x01, kOk}}},
           Case{{0xFF, 0xFF}, {{0xFF, kOk}}},                      // escaped data 0xFF
           Case{{0xFF, 0x00, 0x41}, {{0x41, LineError::Parity}}},  // marked error char
           Case{{0xFF, 0x00, 0x00}, {{0x00, LineError::Break}}},   // break
           Case{{0xFF, 0x00, 0xFF}, {{0xFF, LineError::Parity}}},  // error on byte 0xFF
           Case{{0x10, 0xFF, 0xFF, 0x20}, {{0x10, kOk}, {0xFF, kOk}, {0x20, kOk}}},
           Case{{0xFF, 0x37}, {{0x37, LineError::Parity}}},  // malformed: unreliable
           Case{{}, {}},
       }) {
    ParmrkDecoder d;
    EXPECT_EQ(run(d, c.raw), c.chars);
    EXPECT_FALSE(d.mid_escape());
  }
}

TEST(UssParmrk, EscapeStraddlesCalls) {
  ParmrkDecoder d;
  EXPECT_EQ(run(d, {0x02, 0xFF}), (std::vector<RxChar>{{0x02, kOk}}));
  EXPECT_TRUE(d.mid_escape());
  EXPECT_EQ(run(d, {0xFF, 0x03}), (std::vector<RxChar>{{0xFF, kOk}, {0x03, kOk}}));
  // 0xFF | 0x00 | c over three reads
  EXPECT_EQ(run(d, {0xFF}), std::vector<RxChar>{});
  EXPECT_EQ(run(d, {0x00}), std::vector<RxChar>{});
  EXPECT_TRUE(d.mid_escape());
  EXPECT_EQ(run(d, {0x5A, 0x01}), (std::vector<RxChar>{{0x5A, LineError::Parity}, {0x01, kOk}}));
  // 0xFF 0x00 | 0x00: a break split after the marker
  EXPECT_EQ(run(d, {0xFF, 0x00}), std::vector<RxChar>{});
  EXPECT_EQ(run(d, {0x00}), (std::vector<RxChar>{{0x00, LineError::Break}}));
}

TEST(UssParmrk, ResetDropsHalfEscape) {
  ParmrkDecoder d;
  EXPECT_TRUE(run(d, {0xFF, 0x00}).empty());
  d.reset();
  EXPECT_EQ(run(d, {0x41}), (std::vector<RxChar>{{0x41, kOk}}));
}

TEST(UssParmrk, NeverMoreCharsThanBytes) {
  // Worst case for output: a pending 0xFF followed by plain bytes.
  ParmrkDecoder d;
  (void)run(d, {0xFF});
  std::array<std::uint8_t, 3> raw{0x37, 0x38, 0x39};
  std::array<RxChar, 3> out{};
  EXPECT_EQ(d.decode(raw, out), 3U);
  EXPECT_EQ(out[0], (RxChar{0x37, LineError::Parity}));
  EXPECT_EQ(out[2], (RxChar{0x39, kOk}));
}

}  // namespace
}  // namespace liftd::uss
