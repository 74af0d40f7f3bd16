// The `dcp` object of `status`: what only a DCP drive has (its I0 mode, the S0..S7 status bits,
// the extended status, why the handshake has not completed). docs/api.md, `status`.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "dcp/frame.hpp"
#include "dcp/master_link.hpp"
#include "io/line_echo.hpp"

namespace liftd::daemon {

/// The DCP facts `status` reports, as the cycle last published them.
struct DcpStatusFacts {
  std::optional<dcp::Protocol> mode;                 ///< nullopt before the I0 reply (DCP 5.12.2)
  std::optional<std::uint8_t> status_byte;           ///< S0..S7 of the last good reply (DCP 4.1)
  std::optional<dcp::ExtendedStatus> extended;       ///< DCP 4.2.1.1; nullopt if never received
  std::string_view handshake_problem;                ///< empty once the handshake is complete
  io::EchoMode echo_mode = io::EchoMode::Off;        ///< drive.echo
  io::EchoState echo_state = io::EchoState::Absent;  ///< what the cycle knows of the echo
  bool operator==(const DcpStatusFacts&) const = default;
};

/// {"mode", "status", "extended", "handshake_problem", "line_echo"}: the `dcp` object of
/// `status`.
nlohmann::json dcp_status_json(const DcpStatusFacts& facts);
/// The S0..S7 bits by name.
nlohmann::json to_json(const dcp::Status& status);
/// The extended status bits by name.
nlohmann::json to_json(const dcp::ExtendedStatus& extended);

}  // namespace liftd::daemon
