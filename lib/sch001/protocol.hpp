// The SCH001 hydraulic power-unit card's CAN protocol, sans-I/O: identifiers, the card's status
// frame, our answer, the timeout commands. The card's document ("CAN Kommunikation mit
// Steuerung") is cited by its chapter numbers: 1.6 identifiers, 2 card parameters P479/P480,
// 3a-f the frames. CAN 2.0A, 11-bit identifiers, 125 kbit/s (3a).
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>

#include "can/frame.hpp"

namespace liftd::sch001 {

/// P479 = 0 means base 0x550 (2.1).
inline constexpr std::uint32_t kDefaultBase = 0x550;
/// P480 = 49: the card accepts our commands; the controller's node is base + 49 (0x581) (1.6, 2.2).
inline constexpr std::uint32_t kDefaultControllerNode = 49;
/// The card reserves 96 consecutive identifiers from its base (1.6).
inline constexpr std::uint32_t kReservedIds = 96;

/// The identifiers of one card.
struct Ids {
  std::uint32_t to_card = kDefaultBase + 1;                         ///< we send here (base + 1)
  std::uint32_t from_card = kDefaultBase + kDefaultControllerNode;  ///< the card sends here
  bool operator==(const Ids&) const = default;
};

/// The identifiers for card parameters P479 (base, 0 = 0x550) and P480 (our node offset; 0
/// makes the card ignore us, so it is refused). nullopt with `why` set when the pair cannot
/// work: P480 outside 2..95 (1 is the card's own receive id, 96 leaves the reserved block), or
/// the block of 96 identifiers past 0x7FF.
std::optional<Ids> ids_for(std::uint32_t p479, std::uint32_t p480, std::string* why = nullptr);

// ---- frames from the card (3b, 3f) ----

/// First byte of the card's status frame (3b).
inline constexpr std::uint8_t kStatusFrame = 0x61;
/// The status frame is 2 bytes: 0x61 and the status byte (3b).
inline constexpr std::uint8_t kStatusFrameLength = 2;
/// The card sends its status frame every 100 ms (3b: "jede 100ms"); our signals reach it only in
/// the answer (3c), so a change of signal takes effect at one of these moments.
inline constexpr std::chrono::milliseconds kStatusPeriod{100};
/// The card enables our 10 s timeout (3f).
inline constexpr std::uint8_t kEnableTimeout = 0x52;
/// The card disables our timeout (3f).
inline constexpr std::uint8_t kDisableTimeout = 0x5A;

/// The card's status byte, MSB first: ERR PNP2 AVV T1 P1 P2 RDY PNP1; 1 = relay on / output
/// high (3b). AVV and PNP2 are valid in single-unit systems only.
struct CardStatus {
  bool err = false;   ///< bit 7: ERR relay (fault); cumulative over units
  bool pnp2 = false;  ///< bit 6: PNP2 output (single unit only)
  bool avv = false;   ///< bit 5: AVV relay, motor start/supply (single unit only)
  bool t1 = false;    ///< bit 4: T1 relay, oil temperature
  bool p1 = false;    ///< bit 3: P1 relay, minimum/maximum pressure
  bool p2 = false;    ///< bit 2: P2 relay, overpressure
  bool rdy = false;   ///< bit 1: RDY relay (ready)
  bool pnp1 = false;  ///< bit 0: PNP1 output
  static CardStatus from_byte(std::uint8_t byte) noexcept;
  std::uint8_t to_byte() const noexcept;
  bool operator==(const CardStatus&) const = default;
};

struct StatusFrame {
  CardStatus status;
};
struct TimeoutCommand {
  bool enable = true;  ///< 0x52: true, 0x5A: false
};
/// Why a frame from the card's identifier was not taken.
enum class Rejection : std::uint8_t {
  WrongLength,       ///< a status frame that is not 2 bytes, or an empty frame
  UnknownFirstByte,  ///< none of 0x61, 0x52, 0x5A
};
std::string_view to_string(Rejection rejection) noexcept;

using CardMessage = std::variant<StatusFrame, TimeoutCommand, Rejection>;

/// Decodes the data of a frame received on the card's identifier. The document gives no length
/// for the timeout commands (3f): any length from 1 is taken, the first byte decides.
CardMessage decode_card_frame(const can::Frame& frame) noexcept;

// ---- frames to the card (3c, 3f) ----

/// First byte of our answer (3c).
inline constexpr std::uint8_t kCommandFrame = 0x68;
/// Our answer is 4 bytes (3c).
inline constexpr std::uint8_t kCommandFrameLength = 4;
/// Our acknowledgement of 0x52 (3f).
inline constexpr std::uint8_t kTimeoutEnabledAck = 0x65;
/// Our acknowledgement of 0x5A (3f).
inline constexpr std::uint8_t kTimeoutDisabledAck = 0x6B;

/// Our command byte, MSB first: SP3 SP2 SP1 SFY MSP HSP DW UP; 1 = command (3c, 1.4).
struct CommandBits {
  bool sp3 = false;  ///< bit 7: fast down when card P453 = 1
  bool sp2 = false;  ///< bit 6: with HSP, speed V4
  bool sp1 = false;  ///< bit 5: with HSP, speed V3
  bool sfy = false;  ///< bit 4: motors switched on (set only when all are on)
  bool msp = false;  ///< bit 3: inspection / speed V2
  bool hsp = false;  ///< bit 2: fast speed up (and down when card P435 = 0)
  bool dw = false;   ///< bit 1: travel down
  bool up = false;   ///< bit 0: travel up
  static CommandBits from_byte(std::uint8_t byte) noexcept;
  std::uint8_t to_byte() const noexcept;
  bool any() const noexcept { return to_byte() != 0; }
  bool operator==(const CommandBits&) const = default;
};

/// Everything our answer carries.
struct Command {
  CommandBits bits;
  std::uint8_t current_floor = 0;      ///< where the car is (0 = lowest), updated at each stop
  std::uint8_t destination_floor = 0;  ///< where the travel ends (0 = lowest)
  bool operator==(const Command&) const = default;
};

/// Our 4-byte answer on `ids.to_card`.
can::Frame encode_command(const Ids& ids, const Command& command) noexcept;
/// Our one-byte acknowledgement of a timeout command on `ids.to_card`.
can::Frame encode_timeout_ack(const Ids& ids, bool enabled) noexcept;

}  // namespace liftd::sch001
