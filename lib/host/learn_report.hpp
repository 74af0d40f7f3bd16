// The learning travel's result as every lift reports it: the learned table beside the configured
// one, floor by floor, in the `learn` reply and event and in the journal.
#pragma once

#include <cstddef>
#include <span>

#include <nlohmann/json.hpp>

#include "api/server.hpp"
#include "config/config.hpp"
#include "lift/learning_travel.hpp"
#include "lift/level_learner.hpp"

namespace liftd::daemon {

/// What `floors[].level_mm` changes need before they take effect (the floors are read at start).
inline constexpr const char* kLearnTakesEffect =
    "floors[].level_mm is read when liftd starts: restart liftd after writing the learned levels "
    "(liftctl learn --apply); a reload keeps the running floors and names them in the journal";

/// The `learn` result: accepted, verdict, reason, zones_found, floors (configured_mm,
/// learned_mm, difference_mm, zone_mm for each floor a zone was found for), takes_effect.
nlohmann::json learn_result_json(const config::Config& config, lift::LearnJudgement judgement,
                                 std::span<const lift::LearnedZone> zones, std::size_t zones_seen);

/// The same from a learning travel's record (every lift's controller publishes one).
nlohmann::json learn_result_json(const config::Config& config, const lift::LearnRecord& record);

/// Journals the result and sends the `learn` event to the watchers.
void report_learn(api::Server& server, const nlohmann::json& result);

}  // namespace liftd::daemon
