#include "kinds/config_schema.hpp"

#include "dcp/config/config_rules.hpp"
#include "sch001/config/config_rules.hpp"
#include "uss/config/config_rules.hpp"

namespace liftd::kinds {

const config::Schema& config_schema() {
  static const config::Schema schema = [] {
    config::Schema s;
    s.add(config::log_keys());
    s.add(config::drive_keys());
    s.add(dcp::config_rules());
    s.add(config::rt_keys());
    s.add(config::api_keys());
    s.add(config::inputs_keys());
    s.add(config::record_keys());
    s.add(config::eta_keys());
    // Floor names and levels follow the DCP display (appendix A) and I9 (DCP 5.12.9) for every
    // kind, so a building's floors stay valid when its drive changes.
    s.add(config::floors_keys(dcp::floor_rules()));
    s.add(config::position_keys());
    s.add(config::travel_keys());
    s.add(config::can_keys());
    s.add(sch001::config_rules());
    s.add(uss::config_rules());
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
