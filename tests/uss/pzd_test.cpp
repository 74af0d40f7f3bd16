// PZD (C 5): control and status word bits, normalisation, the broadcast enable rules of the
// appendix.
#include <gtest/gtest.h>

#include <array>

#include "uss/pzd.hpp"

namespace liftd::uss {
namespace {

TEST(UssPzd, ControlAndStatusBits) {
  // C 5.2.1 Tabellen 5.2-5.6: bits 0..10.
  const std::array<std::uint16_t, 11> stw_bits{stw::kOn,
                                               stw::kNoOff2,
                                               stw::kNoOff3,
                                               stw::kEnableOperation,
                                               stw::kRampGeneratorEnable,
                                               stw::kRampStart,
                                               stw::kSetpointEnable,
                                               stw::kFaultAcknowledge,
                                               stw::kJog1,
                                               stw::kJog2,
                                               stw::kControlByPlc};
  const std::array<std::uint16_t, 11> zsw_bits{zsw::kReadyToSwitchOn,  zsw::kReady,
                                               zsw::kOperationEnabled, zsw::kFault,
                                               zsw::kNoOff2,           zsw::kNoOff3,
                                               zsw::kSwitchOnInhibit,  zsw::kWarning,
                                               zsw::kSetpointReached,  zsw::kPlcControlRequested,
                                               zsw::kFrequencyReached};
  for (unsigned bit = 0; bit < 11; ++bit) {
    EXPECT_EQ(stw_bits[bit], 1U << bit);
    EXPECT_EQ(zsw_bits[bit], 1U << bit);
    EXPECT_FALSE(kControlWordBitNames[bit].empty());
    EXPECT_FALSE(kStatusWordBitNames[bit].empty());
    for (char ch : kControlWordBitNames[bit])
      EXPECT_TRUE((ch >= 'a' && ch <= 'z') || ch == '_' || (ch >= '0' && ch <= '9'));
  }
  EXPECT_EQ(kControlWordBitNames[10], "control_by_plc");
  EXPECT_EQ(kStatusWordBitNames[6], "switch_on_inhibit");
  // A typical "run" control word: ON, no OFF2/OFF3, enable, ramp enabled/running, setpoint
  // enabled, control by PLC.
  EXPECT_EQ(stw::kOn | stw::kNoOff2 | stw::kNoOff3 | stw::kEnableOperation |
                stw::kRampGeneratorEnable | stw::kRampStart | stw::kSetpointEnable |
                stw::kControlByPlc,
            0x047F);
}

TEST(UssPzd, Normalisation) {
  const Normalisation n;  // 4000 hex = 100 %
  EXPECT_EQ(n.to_raw(100.0), 0x4000);
  EXPECT_EQ(n.to_raw(50.0), 0x2000);
  EXPECT_EQ(n.to_raw(-100.0), -0x4000);
  EXPECT_EQ(n.to_raw(1000.0), 32767);    // clamped
  EXPECT_EQ(n.to_raw(-1000.0), -32768);  // clamped
  EXPECT_EQ(n.to_raw(0.003), 0);         // rounds to nearest step (0.0061 %)
  EXPECT_DOUBLE_EQ(n.from_raw(0x2000), 50.0);
  EXPECT_DOUBLE_EQ(n.from_raw(-0x4000), -100.0);
  const Normalisation hz{0x4000, 50.0};  // 4000 hex = 50 Hz
  EXPECT_EQ(hz.to_raw(25.0), 0x2000);
  EXPECT_DOUBLE_EQ(hz.from_raw(0x1000), 12.5);
  const Normalisation broken{0, 0.0};
  EXPECT_EQ(broken.to_raw(5.0), 0);
  EXPECT_EQ(broken.from_raw(5), 0.0);
}

TEST(UssPzd, ApplyBroadcastRules) {
  // Appendix table: PZD1 needs a bit 1 and mask b, PZD4 a bit 4 and mask c, PZD5 a bit 5 and
  // mask d, PZD 2, 3, 6..15 their bit in a only, PZD16 never.
  std::array<std::uint16_t, 16> received{};
  received.fill(0xFFFF);
  BroadcastEnable be;
  be.enable = true;
  be.pzd_words = static_cast<std::uint16_t>(pzd_word_bit(1) | pzd_word_bit(2) | pzd_word_bit(4) |
                                            pzd_word_bit(5) | pzd_word_bit(15));
  be.mask_pzd1 = 0x0020;
  be.mask_pzd4 = 0x00F0;
  be.mask_pzd5 = 0x0000;
  std::array<std::uint16_t, 16> current{};
  apply_broadcast(be, received, current);
  EXPECT_EQ(current[0], 0x0020);   // only bit 5
  EXPECT_EQ(current[1], 0xFFFF);   // PZD2 enabled
  EXPECT_EQ(current[2], 0x0000);   // PZD3 not enabled
  EXPECT_EQ(current[3], 0x00F0);   // PZD4 masked by c
  EXPECT_EQ(current[4], 0x0000);   // PZD5 enabled but mask d empty
  EXPECT_EQ(current[14], 0xFFFF);  // PZD15
  EXPECT_EQ(current[15], 0x0000);  // PZD16 never
  EXPECT_EQ(pzd_word_bit(16), 0);
  EXPECT_EQ(pzd_word_bit(0), 0);
  // Without the flag in word a bit 0 nothing is taken.
  be.enable = false;
  std::array<std::uint16_t, 16> untouched{};
  apply_broadcast(be, received, untouched);
  EXPECT_EQ(untouched, (std::array<std::uint16_t, 16>{}));
}

TEST(UssPzd, BroadcastEnableArrayWords) {
  BroadcastEnable be;
  be.enable = true;
  be.pzd_words = 0xFFFF;  // bit 0 comes from `enable` only
  be.mask_pzd1 = 0x1111;
  be.mask_pzd4 = 0x2222;
  be.mask_pzd5 = 0x3333;
  Pkw pkw;
  encode_broadcast_enable(be, pkw);
  EXPECT_EQ(pkw.pke(), 0xFFFF);
  EXPECT_EQ(pkw.ind, 0x1111);
  EXPECT_EQ(pkw.pwe_count, 2);
  EXPECT_EQ(pkw.pwe[0], 0x2222);
  EXPECT_EQ(pkw.pwe[1], 0x3333);
  const BroadcastEnable back = decode_broadcast_enable(pkw);
  EXPECT_TRUE(back.enable);
  EXPECT_EQ(back.pzd_words, 0xFFFE);
  EXPECT_EQ(back.mask_pzd5, 0x3333);
  be.enable = false;
  EXPECT_EQ(be.word_a(), 0xFFFE);
}

}  // namespace
}  // namespace liftd::uss
