// The DCP lift's section of the configuration file (`dcp.*`): the DCP link to the drive.
// Its keys, checks and summary are in config_rules.cpp; the loader holds it in
// config::Config::kinds (lib/config/config.hpp), read with dcp_section().
#pragma once

#include <string>

#include "common/defaults.hpp"
#include "config/config.hpp"
#include "dcp/defaults.hpp"
#include "drive/drive.hpp"

namespace liftd::config {

/// `dcp.*`
struct DcpConfig {
  static constexpr drive::Kind kKind = drive::Kind::Dcp;  ///< the kind it belongs to

  /// dcp.manufacturer, sent in I0 (DCP 5.12.2.3); "LD" is in no company's row of that table.
  std::string manufacturer = "LD";
  std::string language = "EN";  ///< dcp.language, sent in I0
  char data_info_type = '0';    ///< dcp.data_info_type, set with I1 (DCP 4.2)
  bool extended_position = defaults::kExtendedPosition;    ///< dcp.extended_position
  int link_fault_frames = defaults::kLinkFaultFrames;      ///< dcp.link_fault_frames (DCP 7.3)
  int link_recover_frames = defaults::kLinkRecoverFrames;  ///< dcp.link_recover_frames (DCP 7.3)
  int request_timeout_ms = defaults::kRequestTimeoutMs;    ///< dcp.request_timeout_ms
};

/// The `dcp.*` section of `config` (its defaults until the file sets a key).
inline const DcpConfig& dcp_section(const Config& config) {
  return config.kinds.get<DcpConfig>();
}
/// The `dcp.*` section of `config`, to change.
inline DcpConfig& dcp_section(Config& config) {
  return config.kinds.get<DcpConfig>();
}

}  // namespace liftd::config
