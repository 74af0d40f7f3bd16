#include "uss/host/commands.hpp"

#include <limits>
#include <string>
#include <utility>

#include "api/schema.hpp"
#include "drive/drive.hpp"
#include "uss/pkw.hpp"
#include "uss/registry_entry.hpp"
#include "uss/telegram.hpp"

namespace liftd::uss {

using api::Access;
using api::Call;
using api::Responder;
using api::Result;
using daemon::kParameterTargets;
using daemon::ParameterArgs;
using daemon::ParameterTarget;
using daemon::UssCommandBackend;

namespace {

// C 4.2.2: the element index is one byte of IND; a word or double word of PWE carries the value,
// written signed or unsigned.
constexpr std::int64_t kMaxElementIndex = std::numeric_limits<std::uint8_t>::max();
constexpr std::int64_t kMaxDword = std::numeric_limits<std::uint32_t>::max();
constexpr std::int64_t kMinDword = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t kMaxWord = std::numeric_limits<std::uint16_t>::max();
constexpr std::int64_t kMinWord = std::numeric_limits<std::int16_t>::min();

ParameterArgs parameter_args(const nlohmann::json& request) {
  ParameterArgs args;
  if (request.contains("address")) args.address = request.at("address").get<int>();
  args.pnu = request.at("pnu").get<int>();
  args.target = api::enum_of<ParameterTarget>(kParameterTargets,
                                              api::arg_or<std::string>(request, "target", "value"));
  args.index = api::arg_or<int>(request, "index", 0);
  return args;
}

}  // namespace

void RegistryEntry::add_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  UssCommandBackend* const uss = dynamic_cast<UssCommandBackend*>(&backend);
  // The answer on a dispatcher without a drive kind (see api::served_by).
  const std::string kNotUssRefusal = "this lift's drive has no parameter channel";

  // USS A 4.3: ADR bits 0..4 carry the slave address; C 4.2.1.3: the PNU is PKE bits 0..10.
  const api::ArgSpec address = api::int_arg("address", false, 0, uss::kMaxSlaveAddress,
                                            "USS slave address (default: the drive)");
  const api::ArgSpec pnu = api::int_arg("pnu", true, 0, uss::kMaxPnu, "parameter number (PNU)");
  const api::ArgSpec index =
      api::int_arg("index", false, 0, kMaxElementIndex,
                   "element of an array, description or text (IND), passed to the drive unchanged");

  dispatcher.add({"uss_read",
                  Access::Read,
                  {address, pnu,
                   api::choice_arg("target", false, api::names_of(kParameterTargets),
                                   "value (default), array element, description element or text"),
                   index},
                  "read a parameter of a USS slave (PKW request)",
                  api::served_by(uss, kNotUssRefusal,
                                 [](UssCommandBackend& b, const Call& call, Responder done) {
                                   b.parameter(parameter_args(call.request), std::move(done));
                                 }),
                  drive::Capability::Parameters});

  dispatcher.add(
      {"uss_write",
       Access::Control,
       {address, pnu,
        api::choice_arg("target", false, {"value", "array"}, "value (default) or array element"),
        index, api::int_arg("value", true, kMinDword, kMaxDword, "the new value"),
        api::choice_arg("width", false, {"word", "dword"}, "word (default) or double word"),
        api::flag_arg("eeprom", "also store it in the drive's EEPROM (default false)")},
       "change a parameter of a USS slave (PKW request)",
       api::served_by(uss, kNotUssRefusal,
                      [](UssCommandBackend& b, const Call& call, Responder done) {
                        ParameterArgs args = parameter_args(call.request);
                        args.write = true;
                        args.value = call.request.at("value").get<std::int64_t>();
                        args.dword =
                            api::arg_or<std::string>(call.request, "width", "word") == "dword";
                        args.eeprom = api::arg_or<bool>(call.request, "eeprom", false);
                        if (!args.dword && (args.value < kMinWord || args.value > kMaxWord)) {
                          done(Result::fail(
                              api::ErrorCode::BadRequest,
                              "value " + std::to_string(args.value) +
                                  " does not fit a word (-32768..65535): use \"width\": \"dword\"",
                              "value"));
                          return;
                        }
                        b.parameter(args, std::move(done));
                      }),
       drive::Capability::Parameters});

  dispatcher.add({"uss_mirror",
                  Access::Control,
                  {address},
                  "send a mirror telegram (link test, USS A 5.3)",
                  api::served_by(uss, kNotUssRefusal,
                                 [](UssCommandBackend& b, const Call& call, Responder done) {
                                   std::optional<int> a;
                                   if (call.request.contains("address")) {
                                     a = call.request.at("address").get<int>();
                                   }
                                   b.mirror(a, std::move(done));
                                 }),
                  drive::Capability::Parameters});
}

}  // namespace liftd::uss
