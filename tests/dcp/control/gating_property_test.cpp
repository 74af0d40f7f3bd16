// Property test: random commands, input changes and injected faults against the real
// DcpController and the simulator, over many seeds. Every master frame is checked: no B0, B1 or
// B2 while a gating condition forbids it. The conditions are derived from what the rig fed the
// controller before that frame (status bytes, inputs, position, missing replies, API commands)
// and the spec's rules, never from the controller's own state.
#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <string>

#include "controller_rig.hpp"

namespace liftd::control {
namespace {

using testing::CycleRecord;
using testing::Rig;
using testing::word_of;
using namespace std::chrono_literals;
namespace cb = dcp::command_bit;
namespace sb = dcp::status_bit;

constexpr std::uint8_t kMotionBits = cb::kDriveEnable | cb::kTravel | cb::kStopSwitch;
// DCP 7.3: 10 consecutive missing replies make a link fault; 10 good ones end it.
constexpr int kLinkFaultFrames = 10;
// ControllerConfig defaults: inputs and the API inspection direction go stale after 500 ms.
constexpr auto kInputsTimeout = 500ms;
constexpr auto kInspectionHold = 500ms;

/// The API inspection state the test sent (the controller handles it in the next frame).
struct ApiInspection {
  bool on = false;
  lift::Direction direction = lift::Direction::None;
  MonoTime hold_until{};
};

/// Checks frames one by one, carrying only what the wire and the rig's feed imply.
class GatingChecker {
 public:
  explicit GatingChecker(dcp::Protocol protocol) : protocol_(protocol) {}

  /// The first rule the frame breaks, or an empty string.
  std::string check(const CycleRecord& r, const ApiInspection& api) {
    std::string broken;
    const std::uint8_t motion = r.frame[0] & kMotionBits;
    const bool enable = (r.frame[0] & cb::kDriveEnable) != 0;
    const std::uint8_t nibble = r.frame[0] & 0x0F;
    // Fast start hold as the wire shows it (DCP 12.1.1): a VF speed message, B0 on ever since,
    // no go message (speed-after-fast-start with a real speed) yet.
    if (nibble == 0x9 && word_of(r.frame) == dcp::speed_word(dcp::Speed::VF)) fs_hold_ = true;
    if (!enable ||
        ((nibble == 0xD || nibble == 0xF) && word_of(r.frame) != dcp::speed_word(dcp::Speed::VF))) {
      fs_hold_ = false;
    }

    // DCP 11.1.1 d / 11.1.2 step 4: in DCP4 B2 stays until the drive drops S6 at the level. A
    // frame that clears B2 but keeps B0 while the last reply showed S6 is a stop message at speed
    // (DCP 3.5.3.2), except in the fast start, whose controlled end is that message (DCP 12.2.2).
    // Safety aborts clear B0 with B2 and are judged by the rules below.
    const bool b2 = (r.frame[0] & cb::kStopSwitch) != 0;
    if (protocol_ == dcp::Protocol::Dcp4 && prev_b2_ && !b2 && enable && r.seen &&
        (*r.seen & sb::kBrakeOpen) != 0 && !fs_hold_ && !prev_go_) {
      broken = "DCP 11.1.1 d: B2 withdrawn while S6 is set";
    }
    if (motion != 0 && broken.empty()) {
      const lift::Inputs& in = r.inputs;
      const bool mode = in.inspection || in.recall || api.on;
      const bool api_held = api.on && r.at <= api.hold_until;
      const bool up = in.button_up || (api_held && api.direction == lift::Direction::Up);
      const bool down = in.button_down || (api_held && api.direction == lift::Direction::Down);
      if (!r.seen) {
        broken = "motion before any reply from the drive";
      } else if (link_fault_) {
        broken = "DCP 7.3: link fault (10 missing replies, not yet 10 good ones)";
      } else if (r.at - r.inputs_at > kInputsTimeout) {
        broken = "inputs stale (provider silent > 500 ms)";
      } else if ((*r.seen & sb::kGeneralFault) != 0) {
        broken = "DCP 9.1.6: S3 set";
      } else if (!in.safety_chain_closed) {
        broken = "DCP 9.1.1: safety chain open";
      } else if (!prev_enable_ &&
                 ((*r.seen & sb::kReady) == 0 || (*r.seen & sb::kAdvanceWarning) != 0)) {
        broken = "DCP 9.1.3 / 9.1.5: start without S0 or with S2";
      } else if (mode && up == down) {
        broken = "DCP 9.1.1: inspection / recall without a held button";
      } else if (!mode && !in.doors_locked && !in.door_zone_bridge &&
                 !(fs_hold_ && (r.frame[0] & cb::kTravel) == 0 &&
                   ((r.frame[0] & cb::kStopSwitch) == 0 || word_of(r.frame) == 0))) {
        broken = "doors not locked outside fast start hold, inspection and relevelling";
      } else if (!mode && protocol_ == dcp::Protocol::Dcp4 && !r.position_valid) {
        broken = "DCP4 travel without a valid position";
      }
    }
    prev_enable_ = enable;
    prev_b2_ = b2;
    prev_go_ =
        (nibble == 0xD || nibble == 0xF) && word_of(r.frame) != dcp::speed_word(dcp::Speed::VF);
    // The link supervision as the rig fed it: missing replies in a row, then good ones.
    if (r.reply) {
      ++good_run_;
      bad_run_ = 0;
      if (good_run_ >= kLinkFaultFrames) link_fault_ = false;
    } else {
      ++bad_run_;
      good_run_ = 0;
      if (bad_run_ >= kLinkFaultFrames) link_fault_ = true;
    }
    return broken;
  }

 private:
  dcp::Protocol protocol_;
  bool prev_enable_ = false;
  bool prev_b2_ = false;
  bool prev_go_ = false;  ///< the previous frame was a go after a fast start (DCP 12.1.3)
  bool fs_hold_ = false;
  bool link_fault_ = false;
  int bad_run_ = 0;
  int good_run_ = 0;
};

/// Totals over all seeds, so the property cannot pass by never travelling.
struct Coverage {
  std::uint64_t frames = 0;
  std::uint64_t enabled_frames = 0;
  std::uint64_t finished = 0;
  std::uint64_t aborted = 0;
  std::uint64_t inspection_frames = 0;
  std::uint64_t fast_start_frames = 0;
};

/// One seed: random actions between random runs of cycles; returns the first violation.
// Over 120 lines: one seed read top to bottom, each random action with the checks after it.
std::string run_seed(std::uint32_t seed, Coverage& coverage) {
  std::mt19937 rng(seed);
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  const dcp::Protocol protocol = seed % 2 == 0 ? dcp::Protocol::Dcp4 : dcp::Protocol::Dcp3;
  Rig rig(protocol);
  GatingChecker checker(protocol);
  ApiInspection api;
  std::vector<std::string> actions;
  const std::size_t floors = testing::six_floors().size();
  if (!rig.warm_up()) return "link did not come up";

  std::size_t checked = 0;
  for (int step = 0; step < 60; ++step) {
    std::string what;
    switch (pick(25)) {
      case 0:
      case 1:
      case 2:
      case 3: {
        const auto floor = static_cast<std::size_t>(pick(static_cast<int>(floors)));
        const bool fast = pick(5) == 0;
        rig.post(TravelCommand{floor, std::nullopt, std::nullopt, fast});
        what = "travel " + std::to_string(floor) + (fast ? " fast start" : "");
        break;
      }
      case 4:
        rig.post(StopCommand{});
        what = "stop";
        break;
      case 5:
        rig.post(FastStopCommand{});
        what = "fast stop";
        break;
      case 6:
        rig.post(RelevelCommand{});
        what = "relevel";
        break;
      case 7: {
        api.on = pick(3) != 0;
        api.direction = api.on ? static_cast<lift::Direction>(pick(3)) : lift::Direction::None;
        api.hold_until = rig.now + 15ms + kInspectionHold;  // handled in the next frame
        rig.post(InspectionCommand{api.on, api.direction});
        what = "api inspection " + std::to_string(api.on) + " dir " +
               std::to_string(static_cast<int>(api.direction));
        break;
      }
      case 8:
        rig.post(FastStartCommand{pick(2) == 0 ? FastStartCommand::Action::Go
                                               : FastStartCommand::Action::Abort});
        what = "fast start go/abort";
        break;
      case 9:
        rig.post(CallCommand::adding(static_cast<std::size_t>(pick(static_cast<int>(floors)))));
        what = "call";
        break;
      case 10:
        rig.inputs.doors_locked = rig.inputs.doors_closed = pick(3) != 0;
        what = "doors locked " + std::to_string(rig.inputs.doors_locked);
        break;
      case 11:
        rig.inputs.door_reversal = pick(3) == 0;
        what = "door reversal " + std::to_string(rig.inputs.door_reversal);
        break;
      case 12:
        rig.inputs.safety_chain_closed = pick(4) != 0;
        what = "safety chain " + std::to_string(rig.inputs.safety_chain_closed);
        break;
      case 13:
        rig.inputs.inspection = pick(4) == 0;
        rig.inputs.recall = !rig.inputs.inspection && pick(6) == 0;
        what = "inspection/recall switch";
        break;
      case 14:
        rig.inputs.button_up = pick(2) == 0;
        rig.inputs.button_down = pick(3) == 0;
        what = "buttons";
        break;
      case 15:
        rig.inputs.door_zone_bridge = pick(3) == 0;
        rig.inputs.end_zone_top = pick(5) == 0;
        rig.inputs.end_zone_bottom = pick(5) == 0;
        what = "bridge / end zones";
        break;
      case 16:
        rig.sim.set_general_fault(pick(3) == 0, rig.now);
        what = "S3";
        break;
      case 17:
        rig.sim.set_advance_warning(pick(3) == 0);
        what = "S2";
        break;
      case 18:
        rig.sim.set_not_ready(pick(4) == 0);
        what = "S0 off";
        break;
      case 19:
        rig.position.valid = pick(4) != 0;
        what = "position valid " + std::to_string(rig.position.valid);
        break;
      case 20:
        rig.drop_replies = pick(3) == 0;
        what = "drop replies " + std::to_string(rig.drop_replies);
        break;
      case 21:
        rig.post_inputs = pick(4) != 0;
        what = "inputs posted " + std::to_string(rig.post_inputs);
        break;
      case 23: {
        // DCP 5.1: the communication channel is subordinate; its faults must not end a travel.
        const auto fault = static_cast<dcp::sim::ChannelFault>(pick(3));
        rig.sim.inject_channel(fault, rig.now);
        what = "channel fault " + std::to_string(static_cast<int>(fault));
        break;
      }
      case 22:
        // Drift (the simulator moves the car only while idle).
        rig.sim.set_position_mm(rig.sim.position_mm() + (pick(2) == 0 ? 25.0 : -40.0));
        what = "drift";
        break;
      default:
        what = "wait";
        break;
    }
    actions.push_back(std::to_string(rig.log.size()) + ": " + what);
    const int cycles = 1 + pick(80);
    for (int i = 0; i < cycles; ++i) {
      rig.cycle();
      const CycleRecord& r = rig.log.back();
      std::string broken = checker.check(r, api);
      if (broken.empty() && rig.sim.counters().violations != 0) {
        broken =
            std::string("the simulated drive saw a spec violation: ") +
            (rig.sim.violations(dcp::sim::Violation::StopAtSpeed) != 0 ? "stop message at speed"
                                                                       : "travel without I9");
      }
      ++coverage.frames;
      if ((r.frame[0] & cb::kDriveEnable) != 0) {
        ++coverage.enabled_frames;
        if (r.inputs.inspection || r.inputs.recall || api.on) ++coverage.inspection_frames;
        if (word_of(r.frame) == dcp::speed_word(dcp::Speed::VF)) ++coverage.fast_start_frames;
      }
      ++checked;
      if (!broken.empty()) {
        std::ostringstream out;
        out << "seed " << seed << " cycle " << rig.log.size() - 1 << ": " << broken << "; frame "
            << std::hex << static_cast<int>(r.frame[0]) << " word " << word_of(r.frame) << " seen "
            << static_cast<int>(r.seen.value_or(0)) << std::dec << "\nlast actions:";
        const std::size_t first = actions.size() > 8 ? actions.size() - 8 : 0;
        for (std::size_t a = first; a < actions.size(); ++a) out << "\n  " << actions[a];
        return out.str();
      }
    }
  }
  // The drive's side: what the simulator counts as a spec violation of the master (a stop
  // message at speed, a travel without the I9 owed for the last stop).
  if (rig.sim.counters().violations != 0) {
    std::ostringstream out;
    out << "seed " << seed << ": the simulated drive saw "
        << rig.sim.violations(dcp::sim::Violation::StopAtSpeed) << " stop message(s) at speed and "
        << rig.sim.violations(dcp::sim::Violation::NoPositionAfterStop) << " travel(s) without I9"
        << "\nactions:";
    for (const auto& a : actions) out << "\n  " << a;
    return out.str();
  }
  coverage.finished += rig.travel_events(travel::Event::Type::Finished).size();
  coverage.aborted += rig.travel_events(travel::Event::Type::Aborted).size();
  return checked > 0 ? std::string() : "nothing checked";
}

// 1000 seeds; fewer in the sanitizer build (tests/dcp/control/CMakeLists.txt says why).
#ifndef LIFTD_GATING_SEEDS
#define LIFTD_GATING_SEEDS 1000
#endif

TEST(GatingProperty, NoMotionBitsWhileAConditionForbidsThem) {
  Coverage coverage;
  constexpr std::uint32_t kSeeds = LIFTD_GATING_SEEDS;
  for (std::uint32_t seed = 1; seed <= kSeeds; ++seed) {
    const std::string broken = run_seed(seed, coverage);
    ASSERT_TRUE(broken.empty()) << broken;
  }
  // The property must have been exercised, not passed vacuously.
  EXPECT_GT(coverage.enabled_frames, coverage.frames / 20);
  EXPECT_GT(coverage.finished, kSeeds / 4);
  EXPECT_GT(coverage.aborted, kSeeds / 2);
  EXPECT_GT(coverage.inspection_frames, 100U);
  EXPECT_GT(coverage.fast_start_frames, 100U);
  std::cout << "frames " << coverage.frames << ", with B0 " << coverage.enabled_frames
            << ", travels finished " << coverage.finished << ", aborted " << coverage.aborted
            << ", inspection frames " << coverage.inspection_frames << ", fast start frames "
            << coverage.fast_start_frames << "\n";
}

// The checker itself must catch what it claims to: a frame with B0 while the safety chain is
// open, after S3, and without S0 at the rising edge, each flagged.
TEST(GatingProperty, CheckerFlagsForbiddenFrames) {
  struct Case {
    const char* legend;
    std::uint8_t command;
    std::uint8_t seen;
    bool chain;
    const char* rule_prefix;
  };
  const Case cases[] = {
      {"B0 with the chain open", 0x01, sb::kReady, false, "DCP 9.1.1"},
      {"B2 after S3", 0x05, sb::kReady | sb::kGeneralFault, true, "DCP 9.1.6"},
      {"B0 rising without S0", 0x09, 0x00, true, "DCP 9.1.3"},
      {"B0 rising with S2", 0x09, sb::kReady | sb::kAdvanceWarning, true, "DCP 9.1.3"},
      {"idle frame is always fine", 0x00, sb::kGeneralFault, false, ""},
  };
  // And the stop message at speed: 0101 with S6, then 0001 while S6 is still set.
  {
    GatingChecker checker(dcp::Protocol::Dcp4);
    CycleRecord r;
    r.at = MonoTime{10s};
    r.inputs_at = r.at;
    r.inputs.valid = r.inputs.doors_locked = r.inputs.doors_closed = true;
    r.inputs.safety_chain_closed = true;
    r.seen = r.reply = sb::kReady | sb::kTravelActive | sb::kBrakeOpen;
    r.frame[0] = 0x05;
    EXPECT_EQ(checker.check(r, ApiInspection{}), "");
    r.frame[0] = 0x01;
    EXPECT_EQ(checker.check(r, ApiInspection{}).rfind("DCP 11.1.1 d", 0), 0U);
  }
  for (const Case& c : cases) {
    GatingChecker checker(dcp::Protocol::Dcp4);
    CycleRecord r;
    r.at = MonoTime{10s};
    r.inputs_at = r.at;
    r.frame[0] = c.command;
    r.seen = c.seen;
    r.reply = c.seen;
    r.inputs.valid = r.inputs.doors_locked = r.inputs.doors_closed = true;
    r.inputs.safety_chain_closed = c.chain;
    const std::string broken = checker.check(r, ApiInspection{});
    EXPECT_EQ(broken.rfind(c.rule_prefix, 0), 0U) << c.legend << ": " << broken;
    EXPECT_EQ(broken.empty(), std::string(c.rule_prefix).empty()) << c.legend;
  }
}

}  // namespace
}  // namespace liftd::control
