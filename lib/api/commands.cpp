#include "api/commands.hpp"

#include <algorithm>
#include <memory>
#include <string>

#include "common/version.hpp"
#include "drive/drive.hpp"

namespace liftd::api {
namespace {

ArgSpec flag_arg(std::string name, std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = ArgType::Bool;
  spec.description = std::move(description);
  return spec;
}

ArgSpec int_arg(std::string name, bool required, std::int64_t min, std::int64_t max,
                std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = ArgType::Integer;
  spec.required = required;
  spec.min = min;
  spec.max = max;
  spec.description = std::move(description);
  return spec;
}

ArgSpec choice_arg(std::string name, bool required, std::vector<std::string> choices,
                   std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = ArgType::String;
  spec.required = required;
  spec.choices = std::move(choices);
  spec.description = std::move(description);
  return spec;
}

/// The last status answered and its serialised form: a dispatcher polling a lift at rest asks
/// for the same object again and again, so it is serialised only when it changed.
class StatusCache {
 public:
  std::shared_ptr<const std::string> serialized(StatusSnapshot snapshot) {
    if (!text_ || !(snapshot == last_)) {
      text_ = std::make_shared<const std::string>(dump_compact(to_json(snapshot)));
      last_ = std::move(snapshot);
    }
    return text_;
  }

 private:
  StatusSnapshot last_;
  std::shared_ptr<const std::string> text_;
};

template <typename T>
T arg_or(const nlohmann::json& request, const char* name, T fallback) {
  const auto it = request.find(name);
  return it == request.end() ? fallback : it->get<T>();
}

/// The commands that read the lift's state: status, watch (the event stream), stats, trace.
void add_state_commands(Dispatcher& dispatcher, Backend* b,
                        const std::function<nlohmann::json()>& api_stats) {
  dispatcher.add({"status",
                  Access::Read,
                  {},
                  "link, drive, car, travel, faults, scheduling",
                  [b, cache = std::make_shared<StatusCache>()](const Call&, Responder done) {
                    done(Result::ok_serialized(cache->serialized(b->status())));
                  },
                  kEveryDriveKind});

  dispatcher.add({"watch",
                  Access::Read,
                  {[] {
                    ArgSpec spec =
                        flag_arg("enable", "true starts the event stream, false stops it");
                    spec.required = true;
                    return spec;
                  }()},
                  "start or stop the event stream on this connection",
                  [b](const Call& call, Responder done) {
                    const bool enable = call.request.at("enable").get<bool>();
                    call.session.set_watching(enable);
                    done(Result::ok({{"watching", enable}}));
                    // A new watcher starts from the current state, then sees changes.
                    if (enable) call.session.send_event(event_line("state", to_json(b->status())));
                  },
                  kEveryDriveKind});

  dispatcher.add({"stats",
                  Access::Read,
                  {},
                  "link counters, cycle timing, API counters",
                  [b, api_stats](const Call&, Responder done) {
                    nlohmann::json out = to_json(b->stats());
                    out["api"] = api_stats ? api_stats() : nlohmann::json::object();
                    done(Result::ok(std::move(out)));
                  },
                  kEveryDriveKind});

  dispatcher.add(
      {"trace",
       Access::Read,
       {int_arg("count", false, 1, kMaxTraceEntries, "newest frames to return (default 100)"),
        flag_arg("save",
                 "also write the whole flight recorder, decoded, to a file (needs control "
                 "access; at most one every 10 s)")},
       "the newest DCP frames sent and received",
       [b](const Call& call, Responder done) {
         const bool save = arg_or<bool>(call.request, "save", false);
         if (save && !call.peer.access.control) {
           // A file in the runtime directory (RAM under systemd) per request: not for readers.
           done(Result::fail(ErrorCode::Forbidden,
                             "\"trace\" with \"save\" needs control access; uid " +
                                 std::to_string(call.peer.uid) + " is not in that group"));
           return;
         }
         const auto count = arg_or<std::int64_t>(call.request, "count", 100);
         nlohmann::json frames = nlohmann::json::array();
         for (const auto& entry : b->trace(static_cast<std::size_t>(count))) {
           frames.push_back(to_json(entry));
         }
         nlohmann::json result = {{"frames", std::move(frames)}};
         if (save) {
           Result saved = b->save_trace();
           if (!saved.is_ok()) {
             done(std::move(saved));
             return;
           }
           result.update(saved.value());
         }
         done(Result::ok(std::move(result)));
       },
       kEveryDriveKind});
}

/// The commands that read the drive's display and the daemon's configuration and version.
void add_info_commands(Dispatcher& dispatcher, Backend* b) {
  dispatcher.add({"display",
                  Access::Read,
                  {},
                  "the drive's remote display",
                  [b](const Call&, Responder done) { done(Result::ok(to_json(b->display()))); },
                  drive::Capability::Display});

  dispatcher.add({"config",
                  Access::Read,
                  {},
                  "the effective configuration",
                  [b](const Call&, Responder done) {
                    done(Result::ok({{"config", b->config()}}));
                  },
                  kEveryDriveKind});

  dispatcher.add({"version",
                  Access::Read,
                  {},
                  "daemon and API version",
                  [](const Call&, Responder done) {
                    done(Result::ok({{"version", std::string(kVersion)}, {"api", kApiVersion}}));
                  },
                  kEveryDriveKind});
}

/// The commands to the drive outside a travel: keypad, fault reset, power supply, car load.
void add_drive_commands(Dispatcher& dispatcher, Backend* b) {
  // DCP 5.6.3: the remote keypad has buttons "1" to "5".
  dispatcher.add({"key",
                  Access::Control,
                  {int_arg("key", true, 1, 5, "keypad button 1..5")},
                  "press a button of the drive's remote keypad",
                  [b](const Call& call, Responder done) {
                    b->key(call.request.at("key").get<int>(), std::move(done));
                  },
                  drive::Capability::Keypad});

  dispatcher.add({"drive_reset",
                  Access::Control,
                  {},
                  "ask the drive for a fault reset (I2 'R')",
                  [b](const Call&, Responder done) { b->drive_reset(std::move(done)); },
                  drive::Capability::DriveReset});

  // DCP 5.12.6: supply 'N' mains or 'U' emergency; energy saving '0', '1' or '2'.
  dispatcher.add({"power",
                  Access::Control,
                  {choice_arg("supply", true, {"mains", "emergency"}, "power supply"),
                   int_arg("saving", false, 0, 2, "energy saving mode (default 0)")},
                  "set the power supply mode (I6)",
                  [b](const Call& call, Responder done) {
                    PowerSetting setting;
                    setting.emergency = call.request.at("supply").get<std::string>() == "emergency";
                    setting.saving = arg_or<int>(call.request, "saving", 0);
                    b->power(setting, std::move(done));
                  },
                  drive::Capability::Power});

  // DCP 5.12.8: three BCD digits of percent of the rated load.
  dispatcher.add({"load",
                  Access::Control,
                  {int_arg("percent", true, 0, 999, "car load in percent of rated load")},
                  "send the car load for the next travel (I8)",
                  [b](const Call& call, Responder done) {
                    b->load(call.request.at("percent").get<int>(), std::move(done));
                  },
                  drive::Capability::Load});
}

/// `inputs`: a client sets machine inputs (kInputFlags) and the car position.
void add_inputs_command(Dispatcher& dispatcher, Backend* b) {
  ArgSchema input_args;
  for (const auto& flag : kInputFlags) {
    input_args.push_back(flag_arg(std::string(flag.name), std::string(flag.description)));
  }
  input_args.push_back(int_arg("position_mm", false, -kMaxPositionMm, kMaxPositionMm,
                               "absolute car position in mm from the lowest level"));
  dispatcher.add({"inputs", Access::Inputs, std::move(input_args),
                  "update machine inputs (omitted fields keep their value)",
                  [b](const Call& call, Responder done) {
                    InputUpdate update;
                    for (std::size_t i = 0; i < kInputFlags.size(); ++i) {
                      const auto it = call.request.find(kInputFlags[i].name);
                      if (it != call.request.end()) update.flags[i] = it->get<bool>();
                    }
                    if (const auto it = call.request.find("position_mm");
                        it != call.request.end()) {
                      update.position_mm = it->get<std::int64_t>();
                    }
                    b->update_inputs(update, std::move(done));
                  },
                  kEveryDriveKind});
}

}  // namespace

void add_builtin_commands(Dispatcher& dispatcher, Backend& backend,
                          std::function<nlohmann::json()> api_stats) {
  Backend* b = &backend;
  dispatcher.set_drive_kind(backend.drive_kind());
  add_state_commands(dispatcher, b, api_stats);
  add_info_commands(dispatcher, b);
  add_drive_commands(dispatcher, b);
  add_inputs_command(dispatcher, b);
  add_travel_commands(dispatcher, *b);
  add_sim_command(dispatcher, *b);
  add_parameter_commands(dispatcher, *b);
}

namespace {

TravelArgs travel_args(const nlohmann::json& request) {
  TravelArgs args;
  args.floor = arg_or<int>(request, "floor", 0);
  if (request.contains("speed")) args.speed = request.at("speed").get<std::string>();
  if (request.contains("load_percent")) args.load_percent = request.at("load_percent").get<int>();
  return args;
}

}  // namespace

void add_travel_commands(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  const std::vector<std::string> speeds(drive::kTravelSpeedNames.begin(),
                                        drive::kTravelSpeedNames.end());
  const ArgSpec speed = choice_arg(
      "speed", false, speeds, "speed limit (DCP4: V4 or V3; DCP3: a speed of the installation)");
  // Floors are limited to 64 by the configuration; the backend checks the installed count.
  const ArgSpec floor = int_arg("floor", true, 0, kMaxFloorIndex, "floor index, 0 = lowest");
  ArgSpec optional_floor = floor;
  optional_floor.required = false;

  dispatcher.add({"travel",
                  Access::Control,
                  {floor, speed, int_arg("load_percent", false, 0, 200, "car load in % (I8)")},
                  "travel to a floor, or extend a running DCP4 travel",
                  [b](const Call& call, Responder done) {
                    b->travel(travel_args(call.request), std::move(done));
                  },
                  kEveryDriveKind});
  dispatcher.add({"stop",
                  Access::Control,
                  {},
                  "controlled stop; clears the calls queue",
                  [b](const Call&, Responder done) { b->stop(std::move(done)); },
                  kEveryDriveKind});
  dispatcher.add({"fast_stop",
                  Access::Control,
                  {},
                  "fast stop of the running travel (DCP 13)",
                  [b](const Call&, Responder done) { b->fast_stop(std::move(done)); },
                  drive::Capability::FastStop});
  dispatcher.add({"relevel",
                  Access::Control,
                  {},
                  "relevel to the nearest floor",
                  [b](const Call&, Responder done) { b->relevel(std::move(done)); },
                  kEveryDriveKind});
  dispatcher.add({"inspection",
                  Access::Control,
                  {choice_arg("mode", true, {"on", "off"}, "software inspection on or off"),
                   choice_arg("direction", false, {"up", "down", "none"},
                              "held like a button: repeat within travel.inspection_hold_ms")},
                  "software inspection with a hold-to-run direction",
                  [b](const Call& call, Responder done) {
                    b->inspection(call.request.at("mode") == "on",
                                  arg_or<std::string>(call.request, "direction", "none"),
                                  std::move(done));
                  },
                  kEveryDriveKind});
  dispatcher.add({"fast_start",
                  Access::Control,
                  {choice_arg("action", true, {"arm", "go", "abort"},
                              "arm while the doors close, go when locked, abort (controlled)"),
                   optional_floor, speed},
                  "fast start (DCP 12)",
                  [b](const Call& call, Responder done) {
                    const std::string action = call.request.at("action");
                    if (action == "arm" && !call.request.contains("floor")) {
                      done(Result::fail(ErrorCode::BadRequest, "arm needs a floor", "floor"));
                      return;
                    }
                    b->fast_start(action, travel_args(call.request), std::move(done));
                  },
                  drive::Capability::FastStart});
  dispatcher.add({"calls",
                  Access::Control,
                  {choice_arg("action", false, {"list", "add", "cancel"},
                              "list (default), add or cancel a destination"),
                   optional_floor},
                  "the queue of destinations, served in order",
                  [b](const Call& call, Responder done) {
                    const std::string action = arg_or<std::string>(call.request, "action", "list");
                    std::optional<int> f;
                    if (call.request.contains("floor")) f = call.request.at("floor").get<int>();
                    if (action != "list" && !f) {
                      done(Result::fail(ErrorCode::BadRequest, action + " needs a floor", "floor"));
                      return;
                    }
                    b->calls(action, f, std::move(done));
                  },
                  kEveryDriveKind});
}

namespace {

template <std::size_t N>
std::vector<std::string> names_of(const std::array<std::string_view, N>& names) {
  return {names.begin(), names.end()};
}

template <typename Enum, std::size_t N>
Enum enum_of(const std::array<std::string_view, N>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return static_cast<Enum>(it - names.begin());
}

}  // namespace

void add_sim_command(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  dispatcher.add(
      {"sim",
       Access::Control,
       {choice_arg("action", true, names_of(kSimActions), "what to do to the simulated lift"),
        flag_arg("on", "switches: on (default) or off"),
        choice_arg("fault", false, names_of(kSimReplyFaults), "reply_fault: the fault to inject"),
        choice_arg("channel", false, names_of(kSimChannelFaults),
                   "channel_fault: the communication-channel fault to inject"),
        int_arg("frames", false, 1, kMaxSimFaultFrames,
                "reply_fault: how many replies it affects (default 1)"),
        int_arg("drift_mm", false, -kMaxSimDriftMm, kMaxSimDriftMm,
                "drift: how far the stationary car moves, + up")},
       "fault injection on the simulated lift (liftd --simulate only)",
       [b](const Call& call, Responder done) {
         const nlohmann::json& r = call.request;
         SimRequest request;
         request.action = enum_of<SimAction>(kSimActions, r.at("action").get<std::string>());
         request.on = arg_or<bool>(r, "on", true);
         if (request.action == SimAction::ReplyFault) {
           if (!r.contains("fault")) {
             done(Result::fail(ErrorCode::BadRequest, "reply_fault needs a fault", "fault"));
             return;
           }
           request.fault =
               enum_of<SimReplyFault>(kSimReplyFaults, r.at("fault").get<std::string>());
           request.frames = arg_or<std::uint32_t>(r, "frames", 1);
         }
         if (request.action == SimAction::ChannelFault) {
           if (!r.contains("channel")) {
             done(Result::fail(ErrorCode::BadRequest, "channel_fault needs a channel", "channel"));
             return;
           }
           request.channel =
               enum_of<SimChannelFault>(kSimChannelFaults, r.at("channel").get<std::string>());
         }
         if (request.action == SimAction::Drift) {
           request.drift_mm = arg_or<std::int32_t>(r, "drift_mm", 0);
           if (request.drift_mm == 0) {
             done(Result::fail(ErrorCode::BadRequest, "drift needs a drift_mm other than 0",
                               "drift_mm"));
             return;
           }
         }
         b->sim(request, std::move(done));
       },
       kEveryDriveKind});
}

namespace {

// USS A 4.3: ADR bits 0..4 carry the slave address; C 4.2.1.3: the PNU is PKE bits 0..10;
// C 4.2.2: the element index is one byte of IND.
constexpr std::int64_t kMaxUssAddress = 31;
constexpr std::int64_t kMaxPnu = 2047;
constexpr std::int64_t kMaxElementIndex = 255;
constexpr std::int64_t kMaxDword = 0xFFFFFFFF;
constexpr std::int64_t kMinDword = -0x80000000LL;
constexpr std::int64_t kMaxWord = 0xFFFF;
constexpr std::int64_t kMinWord = -0x8000;

ParameterArgs parameter_args(const nlohmann::json& request) {
  ParameterArgs args;
  if (request.contains("address")) args.address = request.at("address").get<int>();
  args.pnu = request.at("pnu").get<int>();
  args.target =
      enum_of<ParameterTarget>(kParameterTargets, arg_or<std::string>(request, "target", "value"));
  args.index = arg_or<int>(request, "index", 0);
  return args;
}

}  // namespace

void add_parameter_commands(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  const ArgSpec address =
      int_arg("address", false, 0, kMaxUssAddress, "USS slave address (default: the drive)");
  const ArgSpec pnu = int_arg("pnu", true, 0, kMaxPnu, "parameter number (PNU)");
  const ArgSpec index =
      int_arg("index", false, 0, kMaxElementIndex,
              "element of an array, description or text (IND), passed to the drive unchanged");
  dispatcher.add({"uss_read",
                  Access::Read,
                  {address, pnu,
                   choice_arg("target", false, names_of(kParameterTargets),
                              "value (default), array element, description element or text"),
                   index},
                  "read a parameter of a USS slave (PKW request)",
                  [b](const Call& call, Responder done) {
                    b->parameter(parameter_args(call.request), std::move(done));
                  },
                  drive::Capability::Parameters});
  dispatcher.add(
      {"uss_write",
       Access::Control,
       {address, pnu,
        choice_arg("target", false, {"value", "array"}, "value (default) or array element"), index,
        int_arg("value", true, kMinDword, kMaxDword, "the new value"),
        choice_arg("width", false, {"word", "dword"}, "word (default) or double word"),
        flag_arg("eeprom", "also store it in the drive's EEPROM (default false)")},
       "change a parameter of a USS slave (PKW request)",
       [b](const Call& call, Responder done) {
         ParameterArgs args = parameter_args(call.request);
         args.write = true;
         args.value = call.request.at("value").get<std::int64_t>();
         args.dword = arg_or<std::string>(call.request, "width", "word") == "dword";
         args.eeprom = arg_or<bool>(call.request, "eeprom", false);
         if (!args.dword && (args.value < kMinWord || args.value > kMaxWord)) {
           done(Result::fail(ErrorCode::BadRequest,
                             "value " + std::to_string(args.value) +
                                 " does not fit a word (-32768..65535): use \"width\": \"dword\"",
                             "value"));
           return;
         }
         b->parameter(args, std::move(done));
       },
       drive::Capability::Parameters});
  dispatcher.add({"uss_mirror",
                  Access::Control,
                  {address},
                  "send a mirror telegram (link test, USS A 5.3)",
                  [b](const Call& call, Responder done) {
                    std::optional<int> a;
                    if (call.request.contains("address")) a = call.request.at("address").get<int>();
                    b->mirror(a, std::move(done));
                  },
                  drive::Capability::Parameters});
}

}  // namespace liftd::api
