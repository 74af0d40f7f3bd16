// Lines that echo: an RS485 transceiver whose receiver stays enabled while it sends, and most
// USB-RS485 adapters (they switch direction by themselves), give the master back every byte
// it sent, ahead of the other station's reply. The master must read its own frame back
// before the reply, or it takes the frame for the reply (issue #43: a DCP master read its own
// frames back as drive status). Where the kernel drives the line (TIOCSRS485) liftd clears
// SER_RS485_RX_DURING_TX and the line does not echo; anywhere else it may.
//
// Sans-I/O, allocation free, noexcept: the real-time runners (rt::CycleRunner for DCP,
// uss::UssRunner) hold one EchoDetector each and publish its state through an atomic.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace liftd::io {

/// What the link expects of its line (drive.echo).
enum class EchoMode : std::uint8_t {
  Auto,  ///< find out at every port open whether the line echoes
  On,    ///< the line echoes: read back exactly the bytes sent before the reply
  Off,   ///< the line does not echo: the first byte read is the reply's
};

/// What the link knows about its line's echo now.
enum class EchoState : std::uint8_t {
  Unknown,  ///< auto, not decided yet (no port, or no exchange has told yet)
  Present,  ///< the line echoes (configured on, or found out)
  Absent,   ///< the line does not echo (configured off, or found out)
};

/// "auto", "on", "off".
std::string_view to_string(EchoMode mode) noexcept;
/// "unknown", "present", "absent".
std::string_view to_string(EchoState state) noexcept;

/// How the bytes read back compare with the bytes sent.
enum class EchoCheck : std::uint8_t {
  Match,       ///< every byte sent came back unchanged
  Incomplete,  ///< fewer came back than were sent; those that came match
  Collision,   ///< a byte came back changed: another station drove the line meanwhile
};

/// Compares the first bytes of `read` with `sent` (at most sent.size() bytes of `read`).
constexpr EchoCheck check_echo(std::span<const std::uint8_t> sent,
                               std::span<const std::uint8_t> read) noexcept {
  const std::size_t n = std::min(sent.size(), read.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (sent[i] != read[i]) return EchoCheck::Collision;
  }
  return n == sent.size() ? EchoCheck::Match : EchoCheck::Incomplete;
}

/// Whether the line echoes: fixed by the mode, or (Auto) found out anew at every port open.
///
/// Auto decides on the first exchange whose reply the protocol accepted as good (checksum,
/// length, address: a chance match of noise is out of the question), from where that reply
/// stood: behind a faithful copy of the frame sent (Present) or at the start of what was read
/// (Absent). Until then the runner reads each exchange both ways (see the runners), and an
/// exchange that brought back only a copy of the frame sent is no reply at all: an echoing line
/// whose other station is silent looks exactly like that, and taking the copy for the reply is
/// the failure of issue #43.
class EchoDetector {
 public:
  explicit constexpr EchoDetector(EchoMode mode = EchoMode::Auto) noexcept : mode_(mode) {
    port_opened();
  }

  /// A port was (re)opened: another adapter may be behind the name now; Auto forgets.
  constexpr void port_opened() noexcept {
    state_ = mode_ == EchoMode::On    ? EchoState::Present
             : mode_ == EchoMode::Off ? EchoState::Absent
                                      : EchoState::Unknown;
  }

  /// Auto, undecided: a good reply stood behind an echo (`echoed`) or at the start. Returns
  /// true when this decided the state (once per port open).
  constexpr bool good_reply_seen(bool echoed) noexcept {
    if (state_ != EchoState::Unknown) return false;
    state_ = echoed ? EchoState::Present : EchoState::Absent;
    return true;
  }

  constexpr EchoMode mode() const noexcept { return mode_; }
  constexpr EchoState state() const noexcept { return state_; }
  /// The echo is known to be there: the first bytes read are the frame's copy.
  constexpr bool expected() const noexcept { return state_ == EchoState::Present; }
  /// Auto, still finding out.
  constexpr bool undecided() const noexcept { return state_ == EchoState::Unknown; }

 private:
  EchoMode mode_;
  EchoState state_ = EchoState::Unknown;
};

}  // namespace liftd::io
