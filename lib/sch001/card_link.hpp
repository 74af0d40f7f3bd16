// The controller's side of the link to one SCH001 card, sans-I/O: fed every frame received and
// a monotonic time, it answers each status frame with our command (3c), acknowledges the
// timeout commands (3f), supervises the card's silence (3f: 10 s) and never lets a travel bit
// out while the card reports ERR or not RDY (3d, 3e). It owns no socket and no thread: the CAN
// runner feeds it, the travel sequencing sets the command it wants sent.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>

#include "can/frame.hpp"
#include "common/mono_time.hpp"
#include "sch001/protocol.hpp"

namespace liftd::sch001 {

/// 3f: without information from the card for 10 s the controller is in fault.
inline constexpr MonoTime kCardTimeout = std::chrono::seconds(10);

struct CardLinkConfig {
  Ids ids;
  /// AVV and PNP2 are valid only in a single-unit system (3b); with several units they are
  /// not reported.
  bool single_unit = true;
};

/// Frames counted by kind. Rejected frames are never acted on.
struct CardLinkCounters {
  std::uint64_t status_frames = 0;       ///< 0x61 frames taken
  std::uint64_t timeout_commands = 0;    ///< 0x52 / 0x5A frames taken
  std::uint64_t answers = 0;             ///< frames we produced (answers and acknowledgements)
  std::uint64_t wrong_length = 0;        ///< on the card's id, length not as the document says
  std::uint64_t unknown_first_byte = 0;  ///< on the card's id, none of 0x61, 0x52, 0x5A
  std::uint64_t own_id = 0;              ///< someone else sent on our identifier (base + 1)
  std::uint64_t other_id = 0;            ///< identifiers that are neither (a filter let them in)
  std::uint64_t timeouts = 0;            ///< times the card fell silent for 10 s
};

/// What happened to the link state in one call, for the caller's events and journal.
enum class LinkChange : std::uint8_t {
  None,
  FirstHeard,  ///< the first frame from the card on this endpoint (since start or a reopen)
  Silent,      ///< 10 s without information from the card while the timeout is enabled
  Recovered,   ///< a frame from the card after Silent
};

/// What on_frame() made of one frame.
struct FrameResult {
  std::optional<can::Frame> answer;  ///< to send at once on the bus
  LinkChange change = LinkChange::None;
  bool status_changed = false;  ///< the card's status byte differs from the last one
};

class CardLink {
 public:
  /// `start`: when the controller started; the timeout runs from here until the card is heard
  /// (3f: the timeout is enabled whenever the controller is on).
  CardLink(const CardLinkConfig& config, MonoTime start) noexcept;

  /// A frame received from the bus at `now`.
  FrameResult on_frame(const can::Frame& frame, MonoTime now) noexcept;
  /// Timeout supervision: call often (every few 10 ms). Returns Silent once when it trips.
  LinkChange on_tick(MonoTime now) noexcept;
  /// The CAN endpoint was opened again at `now` (after a failure, or a new peer on `unix:`):
  /// what the card said on the old one is void. No status, not heard, our timeout enabled and
  /// running from now (3f: on whenever the controller is on; only a card heard on this
  /// endpoint may switch it off), until a frame from the card arrives on the new endpoint.
  void endpoint_reopened(MonoTime now) noexcept;

  /// The command the next answer carries. Its bits go out only while travel_allowed().
  void set_command(const Command& command) noexcept { command_ = command; }
  const Command& command() const noexcept { return command_; }

  /// A status was heard, the card is not silent, ERR = 0 and RDY = 1 (3d, 3e).
  bool travel_allowed() const noexcept;
  /// The card's last status; nullopt until one was heard.
  const std::optional<CardStatus>& status() const noexcept { return status_; }
  /// AVV and PNP2 are meaningful (single-unit system).
  bool unit_signals_valid() const noexcept { return config_.single_unit; }
  /// Our timeout is enabled (on at start; only the card turns it off, 3f).
  bool timeout_enabled() const noexcept { return timeout_enabled_; }
  /// Heard on the current endpoint (since start, or since endpoint_reopened()).
  bool heard() const noexcept { return heard_; }
  /// Heard at least once since start, on any endpoint.
  bool ever_heard() const noexcept { return ever_heard_; }
  /// Silent for the timeout while it was enabled, and not heard since.
  bool silent() const noexcept { return silent_; }
  /// When the card was last heard (or the start time before that).
  MonoTime last_heard() const noexcept { return last_heard_; }
  const CardLinkCounters& counters() const noexcept { return counters_; }
  const Ids& ids() const noexcept { return config_.ids; }

 private:
  LinkChange heard_at(MonoTime now) noexcept;

  CardLinkConfig config_;
  Command command_{};
  std::optional<CardStatus> status_;
  MonoTime last_heard_;
  bool timeout_enabled_ = true;
  bool heard_ = false;
  bool ever_heard_ = false;
  bool silent_ = false;
  CardLinkCounters counters_{};
};

}  // namespace liftd::sch001
