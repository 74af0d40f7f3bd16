// Fuzzes the flight recorder's DCP decoder: any bytes, either side, any options, any buffer.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "dcp/trace.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  using namespace liftd::dcp;
  const std::uint8_t control = data[0];
  TraceOptions options;
  options.protocol = (control & 1) != 0 ? Protocol::Dcp3 : Protocol::Dcp4;
  options.data_info = static_cast<DataInfoType>('0' + (control >> 1) % 5);
  const FrameSide side = (control & 0x80) != 0 ? FrameSide::Drive : FrameSide::Master;
  const std::size_t cut = data[1];
  const std::span<const std::uint8_t> bytes(data + 2, size - 2);
  TraceBuffer full;
  const auto line = format_frame(bytes, side, options, full);
  if (line.size() >= full.size()) __builtin_trap();  // the longest line must fit
  // A smaller buffer gets a prefix of the same line.
  std::array<char, kTraceLineMax> small{};
  const std::size_t n =
      format_frame(bytes, side, options, std::span<char>(small.data(), cut % small.size()));
  if (n > cut % small.size() || std::memcmp(small.data(), line.data(), n) != 0) __builtin_trap();
  return 0;
}
