// Checks shared by the DCP fuzz targets: what a message decoder accepts must encode and decode
// to the same value; what it refuses must name a reason and point inside the payload.
#pragma once

#include <cstdlib>
#include <span>
#include <variant>

#include "dcp/messages.hpp"

namespace liftd::dcp::fuzz {

inline void check_drive_decoder(std::span<const std::uint8_t> payload) {
  const auto drive = decode_drive_message(payload);
  const auto* init = drive.ok() ? std::get_if<InitReply>(&drive.value) : nullptr;
  if (init != nullptr && init->anomalies != 0) {
    // A tolerated I0 reply (odd maker, version, date, language or length): only its DCP type
    // had to be readable, and it is; such fields are not ours to re-encode.
    if (init->dcp_type != Protocol::ComChan && init->dcp_type != Protocol::Dcp3 &&
        init->dcp_type != Protocol::Dcp4) {
      std::abort();
    }
  } else if (drive.ok()) {
    const auto again = encode(drive.value);
    if (!again.ok()) std::abort();
    const auto back = decode_drive_message(again.value.bytes());
    if (!back.ok() || !(back.value == drive.value)) std::abort();
  } else if (to_string(drive.error).empty() ||
             (!payload.empty() && drive.offset >= payload.size())) {
    std::abort();
  }
}

inline void check_master_decoder(std::span<const std::uint8_t> payload) {
  const auto master = decode_master_message(payload);
  if (master.ok()) {
    const auto again = encode(master.value);
    if (!again.ok()) std::abort();
    const auto back = decode_master_message(again.value.bytes());
    if (!back.ok() || !(back.value == master.value)) std::abort();
  } else if (!payload.empty() && master.offset >= payload.size()) {
    std::abort();
  }
}

}  // namespace liftd::dcp::fuzz
