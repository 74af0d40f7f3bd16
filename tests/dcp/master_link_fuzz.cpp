// libFuzzer target: the master link engine driven by arbitrary replies, gaps, port losses and
// requests. Checks the invariant that matters most: no travel bit leaves unless travel is allowed.
#include <cstdlib>

#include "dcp/master_link.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd::dcp;
  using namespace std::chrono_literals;
  MasterLinkConfig config;
  config.fault_after_bad_frames = 3;
  config.recover_after_good_frames = 2;
  static constexpr std::size_t kStep = 7;  // one control byte + one 6-byte reply
  MasterLink link(config);
  link.set_process(0x07, 0x1234);
  link.set_civil_time({2026, 1, 1, 0, 0, 0});
  liftd::MonoTime now{};
  for (std::size_t i = 0; i + kStep <= size; i += kStep) {
    const std::uint8_t control = data[i];
    now += (control & 0x80) != 0 ? 600ms : 15ms;
    const FrameBytes frame = link.next_frame(now);
    if ((frame[0] & 0x07) != 0 && !link.travel_allowed()) abort();
    switch (control & 0x07) {
      case 0:
        link.on_no_reply(now);
        break;
      case 1:
        link.on_port_lost(now);
        break;
      case 2:
        (void)link.submit(LoadRequest{static_cast<std::uint16_t>(data[i + 1])}, data[i + 2]);
        link.on_reply(std::span<const std::uint8_t, kFrameSize>(data + i + 1, kFrameSize), now);
        break;
      case 3:
        (void)link.submit(
            SwitchRequest{(control & 0x08) ? SwitchFunction::Reset : SwitchFunction::None},
            data[i + 1]);
        link.on_reply(std::span<const std::uint8_t, kFrameSize>(data + i + 1, kFrameSize), now);
        break;
      default: {
        // A reply with a correct checksum, so the channel bytes get through.
        SlaveFrame s{data[i + 1], data[i + 2], data[i + 3], data[i + 4], data[i + 5]};
        link.on_reply(encode(s), now);
        break;
      }
    }
    while (link.pop_completion()) {
    }
    while (link.pop_event()) {
    }
    while (link.pop_drive_error()) {
    }
  }
  return 0;
}
