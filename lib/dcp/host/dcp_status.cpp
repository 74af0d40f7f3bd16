#include "dcp/host/dcp_status.hpp"

#include "host/lift_core.hpp"

#include <string>
#include <utility>

namespace liftd::daemon {
namespace {

std::string_view mode_name(dcp::Protocol protocol) {
  switch (protocol) {
    case dcp::Protocol::ComChan:
      return "ComChan";
    case dcp::Protocol::Dcp3:
      return "DCP3";
    case dcp::Protocol::Dcp4:
      return "DCP4";
  }
  return "ComChan";
}

}  // namespace

// Objects are built key by key, as in api/backend.cpp: status is the request a dispatcher sends
// most.
nlohmann::json to_json(const dcp::Status& s) {
  // S0..S7 (DCP 4.1).
  return api::flags_object({{"ready", s.ready},
                            {"travel_active", s.travel_active},
                            {"advance_warning", s.advance_warning},
                            {"general_fault", s.general_fault},
                            {"below_levelling", s.below_levelling},
                            {"accepted", s.accepted},
                            {"brake_open", s.brake_open},
                            {"message_error", s.message_error}});
}

nlohmann::json to_json(const dcp::ExtendedStatus& e) {
  nlohmann::json j = api::flags_object({{"below_unlocking_speed", e.below_unlocking_speed},
                                        {"below_border_speed", e.below_border_speed},
                                        {"below_overspeed", e.below_overspeed},
                                        {"emergency_reduced_voltage", e.emergency_reduced_voltage},
                                        {"emergency_direction_down", e.emergency_direction_down},
                                        {"motor_temperature_limit", e.motor_temperature_limit},
                                        {"drive_temperature_limit", e.drive_temperature_limit}});
  j["weight_bits"] = e.weight_bits;
  return j;
}

nlohmann::json dcp_status_json(const DcpStatusFacts& facts) {
  nlohmann::json j = nlohmann::json::object();
  j["mode"] = facts.mode ? nlohmann::json(mode_name(*facts.mode)) : nlohmann::json(nullptr);
  // Before the first good reply every bit reads 0, as API 1 reported it.
  j["status"] = to_json(dcp::Status::from_byte(facts.status_byte.value_or(0)));
  j["extended"] = facts.extended ? to_json(*facts.extended) : nlohmann::json(nullptr);
  j["handshake_problem"] = facts.handshake_problem.empty()
                               ? nlohmann::json(nullptr)
                               : nlohmann::json(std::string(facts.handshake_problem));
  j["line_echo"] = line_echo_json(facts.echo_mode, facts.echo_state);
  return j;
}

}  // namespace liftd::daemon
