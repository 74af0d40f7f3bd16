#include "api/commands.hpp"

#include <algorithm>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/version.hpp"
#include "drive/drive.hpp"

namespace liftd::api {
namespace {

/// `calls set`'s `floors`: an array of floor indices; nullopt when `value` is one (filled into
/// `out`), else what is wrong and what is allowed.
std::optional<std::string> floor_list(const nlohmann::json& value, std::vector<int>& out) {
  const std::string allowed = "an array of at most " + std::to_string(kMaxCallsQueued) +
                              " floor indices 0.." + std::to_string(kMaxFloorIndex);
  if (!value.is_array() || value.size() > static_cast<std::size_t>(kMaxCallsQueued)) {
    return "floors must be " + allowed;
  }
  for (const nlohmann::json& floor : value) {
    if (!floor.is_number_integer() || floor.get<std::int64_t>() < 0 ||
        floor.get<std::int64_t>() > kMaxFloorIndex) {
      return "floors must be " + allowed + ": " + floor.dump() + " is not one";
    }
    out.push_back(floor.get<int>());
  }
  return std::nullopt;
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

  dispatcher.add({"travels",
                  Access::Read,
                  {int_arg("last", false, 1, kMaxTravels, "newest travels to return (default 5)")},
                  "the last travels with their curves: position, speed, remaining distance, "
                  "the drive's bits",
                  [b](const Call& call, Responder done) {
                    const auto last = arg_or<std::int64_t>(call.request, "last", 5);
                    done(b->travels(static_cast<std::size_t>(last)));
                  },
                  kEveryDriveKind});

  dispatcher.add(
      {"eta",
       Access::Read,
       {int_arg("floor", false, 0, kMaxFloorIndex,
                "a floor to add to the calls queue: its arrival time and how much later each "
                "queued stop would be"),
        int_arg("position", false, 0, kMaxFloorIndex,
                "where in the calls queue `floor` would go (0: first; default: at the end)")},
       "arrival times: when the car could stand at each floor, from its state and its measured "
       "travels",
       [b](const Call& call, Responder done) {
         EtaArgs args;
         if (call.request.contains("floor")) args.floor = call.request.at("floor").get<int>();
         if (call.request.contains("position")) {
           args.position = call.request.at("position").get<std::size_t>();
         }
         done(b->eta(args));
       },
       kEveryDriveKind});
}

/// The commands that read the daemon's configuration and version.
void add_info_commands(Dispatcher& dispatcher, Backend* b) {
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

/// `drive_reset`: a fault reset asked of the drive (DCP and USS).
void add_drive_reset_command(Dispatcher& dispatcher, Backend* b) {
  dispatcher.add({"drive_reset",
                  Access::Control,
                  {},
                  "ask the drive for a fault reset (I2 'R')",
                  [b](const Call&, Responder done) { b->drive_reset(std::move(done)); },
                  drive::Capability::DriveReset});
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
  add_state_commands(dispatcher, b, api_stats);
  add_info_commands(dispatcher, b);
  add_drive_reset_command(dispatcher, b);
  add_inputs_command(dispatcher, b);
  add_travel_commands(dispatcher, *b);
  add_record_commands(dispatcher, *b);
}

TravelArgs travel_args(const nlohmann::json& request) {
  TravelArgs args;
  args.floor = arg_or<int>(request, "floor", 0);
  if (request.contains("speed")) args.speed = request.at("speed").get<std::string>();
  if (request.contains("load_percent")) args.load_percent = request.at("load_percent").get<int>();
  return args;
}

ArgSpec speed_arg() {
  const std::vector<std::string> speeds(drive::kTravelSpeedNames.begin(),
                                        drive::kTravelSpeedNames.end());
  return choice_arg("speed", false, speeds,
                    "speed limit (DCP4: V4 or V3; DCP3: a speed of the installation)");
}

ArgSpec floor_arg(bool required) {
  // Floors are limited to 64 by the configuration; the backend checks the installed count.
  return int_arg("floor", required, 0, kMaxFloorIndex, "floor index, 0 = lowest");
}

void add_travel_commands(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  const ArgSpec speed = speed_arg();
  const ArgSpec floor = floor_arg(true);
  const ArgSpec optional_floor = floor_arg(false);

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
  ArgSpec floors_list;
  floors_list.name = "floors";
  floors_list.type = ArgType::Any;
  floors_list.description =
      "set: the new queue, first served first (a floor may repeat, not "
      "twice in a row)";
  dispatcher.add(
      {"calls",
       Access::Control,
       {choice_arg("action", false, {"list", "add", "cancel", "insert", "set"},
                   "list (default), add, cancel or insert a destination, or set the queue"),
        optional_floor,
        int_arg("position", false, 0, kMaxCallsQueued - 1,
                "insert: where in the queue (0: first; default: the end)"),
        floors_list},
       "the queue of destinations, served in order",
       [b](const Call& call, Responder done) {
         CallsArgs args;
         args.action = arg_or<std::string>(call.request, "action", "list");
         if (call.request.contains("floor")) args.floor = call.request.at("floor").get<int>();
         const bool needs_floor =
             args.action == "add" || args.action == "cancel" || args.action == "insert";
         if (needs_floor && !args.floor) {
           done(Result::fail(ErrorCode::BadRequest, args.action + " needs a floor", "floor"));
           return;
         }
         if (args.action == "set") {
           const auto it = call.request.find("floors");
           if (it == call.request.end()) {
             done(Result::fail(ErrorCode::BadRequest, "set needs floors", "floors"));
             return;
           }
           if (auto bad = floor_list(*it, args.floors)) {
             done(Result::fail(ErrorCode::BadRequest, *bad, "floors"));
             return;
           }
         }
         if (call.request.contains("position")) {
           args.position = call.request.at("position").get<std::size_t>();
         }
         b->calls(args, std::move(done));
       },
       kEveryDriveKind});
  add_learn_command(dispatcher, backend);
}

void add_learn_command(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  dispatcher.add({"learn",
                  Access::Control,
                  {},
                  "learning travel: find each floor's level from the shaft's level zones; "
                  "answered when it ends",
                  [b](const Call&, Responder done) { b->learn(std::move(done)); },
                  kEveryDriveKind});
}

namespace {

/// The `sim` action named `name`: a shared one, or the own action of the kind that lists it.
SimRequest sim_request_for(std::span<const KindSimActions* const> kinds, const std::string& name) {
  SimRequest request;
  if (const auto it = std::find(kSimActions.begin(), kSimActions.end(), name);
      it != kSimActions.end()) {
    request.name = *it;
    request.shared = static_cast<SimAction>(it - kSimActions.begin());
    return request;
  }
  request.shared.reset();
  for (const KindSimActions* kind : kinds) {
    const auto it = std::find(kind->own.begin(), kind->own.end(), name);
    if (it == kind->own.end()) continue;
    request.name = *it;
    request.owner = kind->kind;
    request.own = static_cast<std::size_t>(it - kind->own.begin());
    return request;
  }
  return request;  // unreachable: `action` was validated against every name
}

}  // namespace

void add_sim_command(Dispatcher& dispatcher, Backend& backend,
                     std::span<const KindSimActions* const> kinds) {
  Backend* b = &backend;
  std::vector<std::string> actions = names_of(kSimActions);
  ArgSchema own_args;
  for (const KindSimActions* kind : kinds) {
    actions.insert(actions.end(), kind->own.begin(), kind->own.end());
    if (kind->own_args != nullptr) {
      for (ArgSpec& arg : kind->own_args()) own_args.push_back(std::move(arg));
    }
  }
  ArgSchema args = {
      choice_arg("action", true, std::move(actions), "what to do to the simulated lift"),
      flag_arg("on", "switches: on (default) or off"),
      choice_arg("fault", false, names_of(kSimReplyFaults), "reply_fault: the fault to inject")};
  for (ArgSpec& arg : own_args) args.push_back(std::move(arg));
  args.push_back(int_arg("frames", false, 1, kMaxSimFaultFrames,
                         "reply_fault: how many replies it affects (default 1)"));
  args.push_back(int_arg("drift_mm", false, -kMaxSimDriftMm, kMaxSimDriftMm,
                         "drift: how far the stationary car moves, + up"));
  std::vector<const KindSimActions*> table(kinds.begin(), kinds.end());
  dispatcher.add(
      {"sim", Access::Control, std::move(args),
       "fault injection on the simulated lift (liftd --simulate only)",
       [b, table = std::move(table)](const Call& call, Responder done) {
         const nlohmann::json& r = call.request;
         SimRequest request = sim_request_for(table, r.at("action").get<std::string>());
         request.on = arg_or<bool>(r, "on", true);
         if (request.shared == SimAction::ReplyFault) {
           if (!r.contains("fault")) {
             done(Result::fail(ErrorCode::BadRequest, "reply_fault needs a fault", "fault"));
             return;
           }
           request.fault =
               enum_of<SimReplyFault>(kSimReplyFaults, r.at("fault").get<std::string>());
           request.frames = arg_or<std::uint32_t>(r, "frames", 1);
         }
         if (request.shared == SimAction::Drift) {
           request.drift_mm = arg_or<std::int32_t>(r, "drift_mm", 0);
           if (request.drift_mm == 0) {
             done(Result::fail(ErrorCode::BadRequest, "drift needs a drift_mm other than 0",
                               "drift_mm"));
             return;
           }
         }
         if (!request.shared) {
           for (const KindSimActions* kind : table) {
             if (kind->kind != request.owner || kind->check == nullptr) continue;
             if (std::optional<Result> refused = kind->check(request.own, r)) {
               done(std::move(*refused));
               return;
             }
           }
           request.request = r;
         }
         b->sim(request, std::move(done));
       },
       kEveryDriveKind});
}

Result sim_action_refused(const SimRequest& request, std::string_view this_lift) {
  return Result::fail(ErrorCode::BadRequest,
                      "\"" + std::string(request.name) +
                          "\" is for the simulator of another drive kind; this lift is " +
                          std::string(this_lift),
                      "action");
}

}  // namespace liftd::api
