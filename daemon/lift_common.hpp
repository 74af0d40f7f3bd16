// What the daemon's lift of every drive kind sets up alike: the runtime directory, the API
// server's configuration and its socket (systemd socket activation), the journal sink of the
// API server, and applying a reloaded configuration to the server.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "api/server.hpp"
#include "can/encoder.hpp"
#include "config/config.hpp"
#include "lift/inputs.hpp"
#include "lift/position_source.hpp"

namespace liftd::daemon {

/// systemd's RuntimeDirectory, else the API socket's directory.
std::string default_runtime_dir(const config::Config& config);
/// The API server's configuration, with the socket systemd passed (or -1: created here).
api::ServerConfig api_server_config(const config::Config& config);
/// The settings a reload may change on a running server (groups, limits, timeouts).
api::ServerConfig api_reload_config(const config::Config& config);
/// Where the API server's log lines go (the journal, component "api").
api::LogFn api_log_sink();
/// The CAN encoder's frame format from position.can_* (position.source "can").
can::EncoderFormat encoder_format(const config::Config& config);
/// Merges an `inputs` update into `merged` (partial updates keep the rest) and hands its position
/// to `feed` (position.source "api"; nullptr otherwise). A refusal, changing nothing, when the
/// update carries a position the configured source does not take.
std::optional<api::Result> merge_inputs(const config::Config& config,
                                        const api::InputUpdate& update, api::Inputs& merged,
                                        lift::PositionFeed* feed);
/// The sequencers' inputs from the API's inputs (every drive kind reads the same machine).
lift::Inputs to_lift(const api::Inputs& inputs);
/// "state changed" -> "state_changed": journal field values are snake_case words.
std::string snake(std::string_view text);

}  // namespace liftd::daemon
