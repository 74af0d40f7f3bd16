// libFuzzer target: any 6 bytes through the frame decoders and the data-word decoders.
#include "dcp/frame.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd::dcp;
  if (size < kFrameSize) return 0;
  std::span<const std::uint8_t, kFrameSize> bytes(data, kFrameSize);
  if (auto m = decode_master(bytes)) {
    if (encode(*m) != FrameBytes{data[0], data[1], data[2], data[3], data[4], data[5]}) abort();
    (void)classify_command(m->command, Protocol::Dcp3);
    (void)classify_command(m->command, Protocol::Dcp4);
    (void)speed_from_word(m->data_word());
  }
  if (auto s = decode_slave(bytes)) {
    for (char t = '0'; t <= '4'; ++t) {
      (void)decode_drive_data(s->data_word(), *data_info_type_from_char(t));
    }
    if (Status::from_byte(s->status).to_byte() != s->status) abort();
  }
  return 0;
}
