// Reload planning: a key-by-key comparison of two configurations as JSON.
#include "daemon/reload.hpp"

#include <algorithm>

#include "kinds/config_schema.hpp"

namespace liftd::daemon {
namespace {

// Appends every changed leaf under `path` (objects recurse; lists and values compare whole).
void diff(const std::string& path, const nlohmann::json& running, const nlohmann::json& next,
          std::vector<KeyChange>& out) {
  if (running.is_object() && next.is_object()) {
    for (const auto& [key, value] : running.items()) {
      const std::string child = path.empty() ? key : path + "." + key;
      diff(child, value, next.contains(key) ? next.at(key) : nlohmann::json(), out);
    }
    for (const auto& [key, value] : next.items()) {
      if (!running.contains(key)) diff(path.empty() ? key : path + "." + key, {}, value, out);
    }
    return;
  }
  if (running != next) out.push_back({path, running.dump(), next.dump()});
}

bool is_live(const std::string& key) {
  const auto& live = live_keys();
  return std::find(live.begin(), live.end(), key) != live.end();
}

}  // namespace

const std::vector<std::string>& live_keys() {
  // Log verbosity, who may use the API and how much: read by the io thread at each use.
  static const std::vector<std::string> keys = {
      "log.level",
      "api.read_group",
      "api.control_group",
      "api.inputs_group",
      "api.max_clients",
      "api.max_requests_per_s",
      "api.idle_timeout_s",
      "api.max_clients_per_uid",
      "api.reserved_clients",
      "api.stalled_reader_timeout_s",
  };
  return keys;
}

ReloadPlan plan_reload(const config::Config& running, const config::Config& next) {
  ReloadPlan plan;
  plan.effective = running;
  std::vector<KeyChange> changes;
  const config::Schema& schema = kinds::config_schema();
  diff("", config::to_json(running, schema), config::to_json(next, schema), changes);
  for (auto& change : changes) {
    (is_live(change.key) ? plan.applied : plan.need_restart).push_back(std::move(change));
  }
  plan.effective.log.level = next.log.level;
  plan.effective.api.read_group = next.api.read_group;
  plan.effective.api.control_group = next.api.control_group;
  plan.effective.api.inputs_group = next.api.inputs_group;
  plan.effective.api.max_clients = next.api.max_clients;
  plan.effective.api.max_requests_per_s = next.api.max_requests_per_s;
  plan.effective.api.idle_timeout_s = next.api.idle_timeout_s;
  plan.effective.api.max_clients_per_uid = next.api.max_clients_per_uid;
  plan.effective.api.reserved_clients = next.api.reserved_clients;
  plan.effective.api.stalled_reader_timeout_s = next.api.stalled_reader_timeout_s;
  return plan;
}

}  // namespace liftd::daemon
