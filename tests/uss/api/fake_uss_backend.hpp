// The API tests' fake of a USS lift: the shared fake (tests/api/fake_backend.hpp) serving the USS
// lift's own commands besides (uss_read, uss_write, uss_mirror: daemon::UssCommandBackend of
// lib/uss/host/commands.hpp).
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "api/fake_backend.hpp"
#include "uss/host/commands.hpp"

namespace liftd::api::testing {

/// Answers the parameter requests as the shared fake answers control commands: noted in
/// requests_seen with every argument as the backend got it (e.g. "parameter -1 4 array 2 write
/// -1 dword", the address -1 when none was given), answered as the test says (control_result,
/// defer) or with success.
class FakeUssBackend : public FakeBackend, public daemon::UssCommandBackend {
 public:
  FakeUssBackend() {
    status_snapshot.drive_kind = drive::Kind::Uss;
    // Not the shared fake's DCP object: a test of status on a USS lift gives its own.
    status_snapshot.details = nlohmann::json::object();
    stats_snapshot.drive_kind = drive::Kind::Uss;
  }

  void parameter(const daemon::ParameterArgs& a, Responder done) override {
    answer("parameter " + std::to_string(a.address.value_or(-1)) + " " + std::to_string(a.pnu) +
               " " + std::string(daemon::kParameterTargets[static_cast<std::size_t>(a.target)]) +
               " " + std::to_string(a.index) +
               (a.write ? " write " + std::to_string(a.value) : "") + (a.dword ? " dword" : "") +
               (a.eeprom ? " eeprom" : ""),
           Result::ok({{"pnu", a.pnu}}), std::move(done));
  }
  void mirror(std::optional<int> address, Responder done) override {
    answer("mirror " + std::to_string(address.value_or(-1)), Result::ok(), std::move(done));
  }
};

}  // namespace liftd::api::testing
