#include "dcp/host/commands.hpp"

#include <string>
#include <utility>

#include "api/commands.hpp"
#include "api/schema.hpp"
#include "dcp/registry_entry.hpp"
#include "drive/drive.hpp"

namespace liftd::daemon {

nlohmann::json to_json(const DisplaySnapshot& d) {
  nlohmann::json cursor = nullptr;
  if (d.cursor_line && d.cursor_column) {
    cursor = {{"line", *d.cursor_line}, {"column", *d.cursor_column}};
  }
  return {{"lines", d.lines}, {"cursor", std::move(cursor)}};
}

nlohmann::json to_json(const PowerSetting& p) {
  return {{"supply", p.emergency ? "emergency" : "mains"}, {"saving", p.saving}};
}

}  // namespace liftd::daemon

namespace liftd::dcp {

using api::Access;
using api::arg_or;
using api::Call;
using api::Responder;
using api::Result;
using daemon::DcpCommandBackend;
using daemon::PowerSetting;

void RegistryEntry::add_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  DcpCommandBackend* const dcp = dynamic_cast<DcpCommandBackend*>(&backend);
  // The answer on a dispatcher without a drive kind (see api::served_by).
  const std::string kNotDcpRefusal = "this lift's drive does not speak DCP";

  dispatcher.add({"display",
                  Access::Read,
                  {},
                  "the drive's remote display",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call&, Responder done) {
                                   done(Result::ok(to_json(b.display())));
                                 }),
                  drive::Capability::Display});

  // DCP 5.6.3: the remote keypad has buttons "1" to "5".
  dispatcher.add({"key",
                  Access::Control,
                  {api::int_arg("key", true, 1, 5, "keypad button 1..5")},
                  "press a button of the drive's remote keypad",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call& call, Responder done) {
                                   b.key(call.request.at("key").get<int>(), std::move(done));
                                 }),
                  drive::Capability::Keypad});

  // DCP 5.12.6: supply 'N' mains or 'U' emergency; energy saving '0', '1' or '2'.
  dispatcher.add({"power",
                  Access::Control,
                  {api::choice_arg("supply", true, {"mains", "emergency"}, "power supply"),
                   api::int_arg("saving", false, 0, 2, "energy saving mode (default 0)")},
                  "set the power supply mode (I6)",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call& call, Responder done) {
                                   PowerSetting setting;
                                   setting.emergency =
                                       call.request.at("supply").get<std::string>() == "emergency";
                                   setting.saving = arg_or<int>(call.request, "saving", 0);
                                   b.power(setting, std::move(done));
                                 }),
                  drive::Capability::Power});

  // DCP 5.12.8: three BCD digits of percent of the rated load.
  dispatcher.add({"load",
                  Access::Control,
                  {api::int_arg("percent", true, 0, 999, "car load in percent of rated load")},
                  "send the car load for the next travel (I8)",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call& call, Responder done) {
                                   b.load(call.request.at("percent").get<int>(), std::move(done));
                                 }),
                  drive::Capability::Load});

  dispatcher.add({"fast_stop",
                  Access::Control,
                  {},
                  "fast stop of the running travel (DCP 13)",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call&, Responder done) {
                                   b.fast_stop(std::move(done));
                                 }),
                  drive::Capability::FastStop});

  dispatcher.add({"fast_start",
                  Access::Control,
                  {api::choice_arg("action", true, {"arm", "go", "abort"},
                                   "arm while the doors close, go when locked, abort (controlled)"),
                   api::floor_arg(false), api::speed_arg()},
                  "fast start (DCP 12)",
                  api::served_by(dcp, kNotDcpRefusal,
                                 [](DcpCommandBackend& b, const Call& call, Responder done) {
                                   const std::string action = call.request.at("action");
                                   if (action == "arm" && !call.request.contains("floor")) {
                                     done(Result::fail(api::ErrorCode::BadRequest,
                                                       "arm needs a floor", "floor"));
                                     return;
                                   }
                                   b.fast_start(action, api::travel_args(call.request),
                                                std::move(done));
                                 }),
                  drive::Capability::FastStart});
}

}  // namespace liftd::dcp
