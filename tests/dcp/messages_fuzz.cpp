// libFuzzer target: any payload through every message decoder, the display model and the
// character set; what decodes must encode and decode to the same value (an I0 reply with
// tolerated odd fields excepted).
#include <cstdlib>
#include <string_view>
#include <variant>

#include "dcp/charset.hpp"
#include "dcp/display.hpp"
#include "dcp/messages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd::dcp;
  const std::span<const std::uint8_t> payload(data, size);

  const auto drive = decode_drive_message(payload);
  const auto* init = drive.ok() ? std::get_if<InitReply>(&drive.value) : nullptr;
  if (init != nullptr && init->anomalies != 0) {
    // A tolerated I0 reply (odd maker, version, date, language or length): only its DCP type
    // had to be readable, and it is; such fields are not ours to re-encode.
    if (init->dcp_type != Protocol::ComChan && init->dcp_type != Protocol::Dcp3 &&
        init->dcp_type != Protocol::Dcp4) {
      abort();
    }
  } else if (drive.ok()) {
    const auto again = encode(drive.value);
    if (!again.ok()) abort();
    const auto back = decode_drive_message(again.value.bytes());
    if (!back.ok() || !(back.value == drive.value)) abort();
  } else if (to_string(drive.error).empty() || (size > 0 && drive.offset >= size)) {
    abort();
  }
  const auto master = decode_master_message(payload);
  if (master.ok()) {
    const auto again = encode(master.value);
    if (!again.ok()) abort();
    const auto back = decode_master_message(again.value.bytes());
    if (!back.ok() || !(back.value == master.value)) abort();
  } else if (size > 0 && master.offset >= size) {
    abort();
  }
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
