// The API tests' fake of a DCP lift: the shared fake (tests/api/fake_backend.hpp) serving the DCP
// lift's own commands besides (display, key, power, load, fast_stop, fast_start:
// daemon::DcpCommandBackend of lib/dcp/host/commands.hpp). Its status at rest is the shared
// fake's, a DCP lift's.
#pragma once

#include <string>
#include <utility>

#include "api/fake_backend.hpp"
#include "dcp/host/commands.hpp"

namespace liftd::api::testing {

/// Answers the DCP commands as the shared fake answers control commands: noted in
/// requests_seen, answered as the test says (control_result, defer) or with success.
class FakeDcpBackend : public FakeBackend, public daemon::DcpCommandBackend {
 public:
  FakeDcpBackend() { display_snapshot.lines = {"Speed    0.00 m/s", "Menu 1", "", ""}; }

  daemon::DisplaySnapshot display() override { return display_snapshot; }
  void key(int button, Responder done) override {
    answer("key " + std::to_string(button), Result::ok(), std::move(done));
  }
  void power(daemon::PowerSetting setting, Responder done) override {
    answer(std::string("power ") + (setting.emergency ? "emergency " : "mains ") +
               std::to_string(setting.saving),
           Result::ok(daemon::to_json(setting)), std::move(done));
  }
  void load(int percent, Responder done) override {
    answer("load " + std::to_string(percent), Result::ok(), std::move(done));
  }
  // No travel control, as the shared fake's travel commands.
  void fast_stop(Responder done) override { no_travel(done); }
  void fast_start(const std::string&, const TravelArgs&, Responder done) override {
    no_travel(done);
  }

  daemon::DisplaySnapshot display_snapshot;  ///< what display() returns

 private:
  static void no_travel(Responder& done) {
    done(Result::fail(ErrorCode::NotReady, kNoTravelControl));
  }
};

}  // namespace liftd::api::testing
