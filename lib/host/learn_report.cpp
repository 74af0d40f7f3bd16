#include "host/learn_report.hpp"

#include <string>

#include "log/log.hpp"

namespace liftd::daemon {

namespace {

std::string reason_of(lift::LearnJudgement judgement, std::span<const lift::LearnedZone> zones,
                      std::size_t zones_seen, std::size_t floors) {
  const auto length = [&](std::size_t i) {
    return i < zones.size() ? std::to_string(zones[i].length_mm()) : std::string("?");
  };
  switch (judgement.verdict) {
    case lift::LearnVerdict::Ok:
      return "one plausible level zone per floor";
    case lift::LearnVerdict::BeganInZone:
      return "the car began the learning travel inside a level zone: its start was not seen";
    case lift::LearnVerdict::EndedInZone:
      return "the car ended the learning travel inside a level zone: its end was not seen";
    case lift::LearnVerdict::ZoneCountDiffers:
      return "found " + std::to_string(zones_seen) + " level zones for " + std::to_string(floors) +
             " floors";
    case lift::LearnVerdict::ZoneTooShort:
      return "level zone " + std::to_string(judgement.zone) + " is " + length(judgement.zone) +
             " mm long, shorter than " + std::to_string(lift::kMinLevelZoneMm) + " mm";
    case lift::LearnVerdict::ZoneTooLong:
      return "level zone " + std::to_string(judgement.zone) + " is " + length(judgement.zone) +
             " mm long, longer than " + std::to_string(lift::kMaxLevelZoneMm) + " mm";
  }
  return "?";
}

}  // namespace

nlohmann::json learn_result_json(const config::Config& config, lift::LearnJudgement judgement,
                                 std::span<const lift::LearnedZone> zones, std::size_t zones_seen) {
  nlohmann::json floors = nlohmann::json::array();
  for (std::size_t i = 0; i < config.floors.size() && i < zones.size(); ++i) {
    const std::int64_t configured = config.floors[i].level_mm;
    const std::int64_t learned = zones[i].level_mm();
    floors.push_back({{"floor", i},
                      {"name", config.floors[i].name},
                      {"configured_mm", configured},
                      {"learned_mm", learned},
                      {"difference_mm", learned - configured},
                      {"zone_mm", zones[i].length_mm()}});
  }
  return {{"accepted", judgement.ok()},
          {"verdict", std::string(lift::to_string(judgement.verdict))},
          {"reason", reason_of(judgement, zones, zones_seen, config.floors.size())},
          {"zones_found", zones_seen},
          {"floors", std::move(floors)},
          {"takes_effect", kLearnTakesEffect}};
}

nlohmann::json learn_result_json(const config::Config& config, const lift::LearnRecord& record) {
  return learn_result_json(
      config, record.judgement,
      std::span<const lift::LearnedZone>(record.zones.data(), record.zone_count),
      record.zones_seen);
}

void report_learn(api::Server& server, const nlohmann::json& result) {
  const bool accepted = result.value("accepted", false);
  log::event(
      accepted ? log::Level::info : log::Level::warn, "travel", "learn",
      {{"verdict", result.value("verdict", "")},
       {"zones_found", std::to_string(result.value("zones_found", 0))}},
      std::string(accepted ? "learning travel: levels learned, " : "learning travel refused: ") +
          result.value("reason", ""));
  server.publish("learn", result);
}

}  // namespace liftd::daemon
