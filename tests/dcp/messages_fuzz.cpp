// libFuzzer target: any payload through every message decoder, the display model and the
// character set; what decodes must encode and decode to the same value (an I0 reply with
// tolerated odd fields excepted).
#include <cstdlib>
#include <string_view>

#include "dcp/charset.hpp"
#include "dcp/display.hpp"
#include "dcp/messages.hpp"
#include "fuzz_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd::dcp;
  const std::span<const std::uint8_t> payload(data, size);

  fuzz::check_drive_decoder(payload);
  fuzz::check_master_decoder(payload);
  const auto keypad = decode_keypad(payload);
  if (keypad.ok() && !encode_keypad(keypad.value).ok()) abort();
  (void)decode_drive_error(payload);

  DisplayModel display;
  (void)display.apply(payload);

  // Character set: bytes -> UTF-8 -> bytes keeps every defined data character.
  const std::string utf8 = to_utf8(payload);
  std::uint8_t out[512];
  (void)from_utf8(std::string_view(reinterpret_cast<const char*>(data), size), out);
  const auto back = from_utf8(utf8, out);
  if (back.ok()) {
    if (back.written != size) abort();
    for (std::size_t i = 0; i < size; ++i) {
      if (out[i] != data[i]) abort();
    }
  }
  return 0;
}
