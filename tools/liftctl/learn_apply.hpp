// liftctl learn: the learning travel's table, and --apply, which writes the learned levels into
// the daemon's configuration file atomically and keeps the old file beside it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace liftctl {

/// The `learn` result as a table: floor, name, configured, learned, difference, zone length,
/// then whether it was accepted and why, and when learned levels take effect.
std::string format_learn_result(const nlohmann::json& result);

/// What --apply did.
struct ApplyOutcome {
  bool ok = false;
  std::string message;  ///< what was written, or why nothing was
};

/// Writes each floor's `learned_mm` of an accepted `learn` result into `floors[i].level_mm` of
/// the JSON configuration file at `path`, every other key and the keys' order as they were. The
/// file's floors must be the ones the result was learned against (same count and configured
/// levels). The old file is kept as `<path>.bak`; the new one is written to a temporary file in
/// the same directory, flushed to disk and renamed over `path`, so a reader sees the old file or
/// the new one, never a part.
ApplyOutcome apply_learned_levels(const std::string& path, const nlohmann::json& result);

}  // namespace liftctl
