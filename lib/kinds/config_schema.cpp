#include "kinds/config_schema.hpp"

#include "kinds/registry.hpp"

namespace liftd::kinds {

const config::Schema& config_schema() {
  static const config::Schema schema = [] {
    config::Schema s;
    s.add(config::log_keys());
    s.add(config::drive_keys());
    // Each kind's section after drive.kind, which picks one of them.
    for_each_entry(Registry{}, [&s](auto entry) { s.add(decltype(entry)::config_rules()); });
    s.add(config::rt_keys());
    s.add(config::api_keys());
    s.add(config::inputs_keys());
    s.add(config::record_keys());
    s.add(config::eta_keys());
    s.add(config::floors_keys(FloorRulesOf::floor_rules()));
    s.add(config::position_keys());
    s.add(config::travel_keys());
    s.add(config::can_keys());
    s.add(config::sim_keys());
    return s;
  }();
  return schema;
}

config::LoadResult parse_config(std::string_view text, std::string_view origin) {
  return config::parse(text, origin, config_schema());
}

config::LoadResult load_config(const std::filesystem::path& path) {
  return config::load_file(path, config_schema());
}

}  // namespace liftd::kinds
