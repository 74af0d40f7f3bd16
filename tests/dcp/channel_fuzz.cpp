// libFuzzer target: any byte stream through the channel parser (two bytes per 15 ms cycle, with
// stalls chosen by the input), every completed frame through the decoder of its mode (checks as in
// fuzz_checks.hpp).
#include <cstdlib>

#include "dcp/channel.hpp"
#include "dcp/display.hpp"
#include "dcp/messages.hpp"
#include "fuzz_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd::dcp;
  using namespace std::chrono_literals;
  ChannelParser parser;
  DisplayModel display;
  liftd::MonoTime now{};
  for (std::size_t i = 0; i < size; ++i) {
    // Every 0xFF byte also stalls the stream for a second, so both timeouts are reached.
    if (data[i] == 0xFF) now += 1000ms;
    if (i % 2 == 0) now += 15ms;
    const ParseStatus status = parser.feed(data[i], now);
    if (status == ParseStatus::Bad && to_string(parser.error()).empty()) abort();
    if (status == ParseStatus::Reset && to_string(parser.reset_reason()).empty()) abort();
    if (status != ParseStatus::Complete) continue;
    const ChannelFrame& frame = parser.frame();
    if (frame.length > kMaxChannelPayload) abort();
    switch (frame.mode) {
      case ChannelMode::Expanded:
        fuzz::check_drive_decoder(frame.payload());
        fuzz::check_master_decoder(frame.payload());
        break;
      case ChannelMode::DriveError:
        (void)decode_drive_error(frame.payload());
        break;
      case ChannelMode::Remote:
        (void)display.apply(frame.payload());
        (void)decode_keypad(frame.payload());
        break;
    }
  }
  (void)parser.poll(now + 2000ms);
  return 0;
}
