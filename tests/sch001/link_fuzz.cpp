// libFuzzer target: any sequence of frames and clock steps through the SCH001 card decoder and
// the controller's card link. Properties from the card's document: a travel bit goes out only
// in the answer to a status frame with ERR = 0 and RDY = 1 (3d, 3e), a rejected frame is never
// answered, and every answer is a 4-byte 0x68 frame or a 1-byte acknowledgement on base + 1.
#include <cstdlib>

#include "sch001/card_link.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd;
  using namespace liftd::sch001;
  CardLink link(CardLinkConfig{}, MonoTime{});
  Command wanted;
  wanted.bits = CommandBits::from_byte(0xFF);
  link.set_command(wanted);
  MonoTime now{};
  std::size_t i = 0;
  while (i + 2 <= size) {
    const std::uint8_t head = data[i++];
    const std::uint8_t length = static_cast<std::uint8_t>(data[i++] % 10);  // 9: too long
    now += std::chrono::milliseconds((head >> 2) * 200);                    // up to 12.6 s
    const std::uint32_t ids[4] = {0x581, 0x551, 0x123, 0x581};
    can::Frame f;
    f.id = ids[head & 3];
    f.length = static_cast<std::uint8_t>(length > 8 ? 8 : length);
    for (std::size_t k = 0; k < f.length && i < size; ++k) f.data[k] = data[i++];
    (void)link.on_tick(now);
    const CardMessage decoded = decode_card_frame(f);
    const FrameResult r = link.on_frame(f, now);
    if (!r.answer) {
      if (f.id == 0x581 && !std::holds_alternative<Rejection>(decoded)) abort();
      continue;
    }
    if (f.id != 0x581 || std::holds_alternative<Rejection>(decoded)) abort();
    if (r.answer->id != 0x551) abort();
    if (std::holds_alternative<TimeoutCommand>(decoded)) {
      if (r.answer->length != 1) abort();
      continue;
    }
    const CardStatus status = std::get<StatusFrame>(decoded).status;
    if (r.answer->length != kCommandFrameLength || r.answer->data[0] != kCommandFrame) abort();
    const bool allowed = !status.err && status.rdy;
    if (r.answer->data[1] != (allowed ? 0xFF : 0x00)) abort();
    if (CardStatus::from_byte(status.to_byte()) != status) abort();
  }
  return 0;
}
