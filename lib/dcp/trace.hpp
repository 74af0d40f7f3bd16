// Readable decoding of DCP frames for the flight recorder dump (rt::FlightRecorder): one text
// column per frame with the message type, the named command or status bits, the data word as a
// speed, remaining distance, deceleration distance or extended status, and the two channel
// bytes. Pure code: the core writes into a caller's buffer and never allocates.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "dcp/frame.hpp"
#include "rt/flight_recorder.hpp"

namespace liftd::dcp {

/// Which side sent a frame.
enum class FrameSide : std::uint8_t {
  Master,  ///< the lift controller (us): command byte first (DCP 3)
  Drive,   ///< the drive: status byte first (DCP 4)
};

/// How frames are read. The data-information-type decides what the drive's data word means
/// (DCP 4.2.2); with the default '0' bit 15 tells deceleration distance from extended status.
struct TraceOptions {
  Protocol protocol = Protocol::Dcp4;                  ///< decides the fast-start nibble (DCP 3.5)
  DataInfoType data_info = DataInfoType::Alternating;  ///< set with I1 (DCP 5.12.3)
};

/// Longest line format_frame() writes; a buffer of this size never truncates.
inline constexpr std::size_t kTraceLineMax = 256;
/// A buffer that always holds a whole decoded line.
using TraceBuffer = std::array<char, kTraceLineMax>;

/// Writes the decoded text of `bytes` (one frame as received: any length) into `out` and
/// returns the characters written (cut at out.size(), no terminating zero). Examples:
///   "travel B0:enable B1:travel B2:stop B4:down | dist 2999 mm | ch STX 0x1C"
///   "drive S0:ready S1:travel S6:brake-open | decel 1430 mm | ch '0' '4'"
///   "BAD-CHECKSUM drive S0:ready | ..."; "short 3/6: 21 7F FF"
std::size_t format_frame(std::span<const std::uint8_t> bytes, FrameSide side,
                         const TraceOptions& options, std::span<char> out) noexcept;

/// format_frame() into `buffer`, as a view of the written text.
std::string_view format_frame(std::span<const std::uint8_t> bytes, FrameSide side,
                              const TraceOptions& options, TraceBuffer& buffer) noexcept;

/// A decoder for rt::write_text(): Tx records are master frames, Rx records drive frames,
/// events get no column. The std::string the interface returns is its only allocation.
rt::FrameDecoder trace_decoder(const TraceOptions& options = {});

}  // namespace liftd::dcp
