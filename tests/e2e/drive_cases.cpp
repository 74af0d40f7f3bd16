#include "e2e/drive_cases.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "drive/drive.hpp"

namespace liftd::e2e {
namespace {

using nlohmann::json;

struct Loaded {
  std::vector<DriveCase> cases;
  std::vector<std::string> problems;
};

template <typename T>
bool take(const json& j, const char* key, T& out, const std::string& where,
          std::vector<std::string>& problems, bool required = true) {
  if (!j.contains(key)) {
    if (required) problems.push_back(where + ": \"" + key + "\" is missing");
    return !required;
  }
  try {
    out = j.at(key).get<T>();
    return true;
  } catch (const json::exception& e) {
    problems.push_back(where + ": \"" + key + "\": " + e.what());
    return false;
  }
}

Loaded load() {
  Loaded out;
  for (const std::string_view kind : drive::kKindNames) {
    const std::string where =
        std::string(LIFTD_TESTS_DIR) + "/" + std::string(kind) + "/e2e_case.json";
    std::ifstream file(where);
    if (!file) {
      out.problems.push_back(where + ": missing; every registered drive kind has one " +
                             "(tests/e2e/drive_cases.hpp says what it holds)");
      continue;
    }
    std::stringstream text;
    text << file.rdbuf();
    const json j = json::parse(text.str(), nullptr, false);
    if (!j.is_object()) {
      out.problems.push_back(where + ": not a JSON object");
      continue;
    }
    for (const auto& [key, value] : j.items()) {
      static const std::vector<std::string> kKnown = {"config",
                                                      "refusal",
                                                      "journal",
                                                      "fault_needs_reset",
                                                      "far_floor",
                                                      "link_fault",
                                                      "learn_slow_mm_per_s",
                                                      "learn_config",
                                                      "status_keys",
                                                      "stats_keys",
                                                      "sim_actions"};
      // A key that starts with "_" is a note for the reader (JSON has no comments).
      if (!key.starts_with('_') && std::find(kKnown.begin(), kKnown.end(), key) == kKnown.end()) {
        out.problems.push_back(where + ": unknown field \"" + key + "\"");
      }
    }
    DriveCase c;
    c.name = kind;
    bool ok = true;
    ok &= take(j, "config", c.config, where, out.problems);
    ok &= take(j, "refusal", c.refusal, where, out.problems);
    ok &= take(j, "journal", c.journal, where, out.problems);
    ok &= take(j, "fault_needs_reset", c.fault_needs_reset, where, out.problems);
    ok &= take(j, "far_floor", c.far_floor, where, out.problems);
    ok &= take(j, "link_fault", c.link_fault, where, out.problems);
    ok &= take(j, "learn_slow_mm_per_s", c.learn_slow_mm_per_s, where, out.problems);
    ok &= take(j, "learn_config", c.learn_config, where, out.problems, false);
    ok &= take(j, "status_keys", c.status_keys, where, out.problems);
    ok &= take(j, "stats_keys", c.stats_keys, where, out.problems);
    json sim;
    ok &= take(j, "sim_actions", sim, where, out.problems);
    ok &= take(sim, "lift_name", c.sim_lift_name, where + " sim_actions", out.problems);
    ok &= take(sim, "shared", c.sim_shared, where + " sim_actions", out.problems);
    ok &= take(sim, "own", c.sim_own, where + " sim_actions", out.problems);
    if (ok) out.cases.push_back(std::move(c));
  }
  return out;
}

const Loaded& loaded() {
  static const Loaded l = load();
  return l;
}

}  // namespace

const std::vector<DriveCase>& drive_cases() {
  return loaded().cases;
}

const std::vector<std::string>& drive_case_problems() {
  return loaded().problems;
}

void expect_a_case_for_every_kind() {
  EXPECT_TRUE(drive_case_problems().empty()) << [] {
    std::string all;
    for (const auto& p : drive_case_problems()) all += p + "\n";
    return all;
  }();
  std::vector<std::string> named;
  for (const DriveCase& c : drive_cases()) named.push_back(c.name);
  std::vector<std::string> registered(drive::kKindNames.begin(), drive::kKindNames.end());
  EXPECT_EQ(named, registered);
}

}  // namespace liftd::e2e
