// The commands of the lift's record (lib/record): `counters`, `counters_reset`, `history` and
// `trend`, the same on every drive kind. The backend answers them from the record it keeps on the
// board's storage (docs/api.md "The lift's record").
#include <algorithm>
#include <string>
#include <vector>

#include "api/commands.hpp"

namespace liftd::api {
namespace {

/// An optional time argument: "YYYY-MM-DD" or "YYYY-MM-DDTHH:MM:SS[.mmm]Z" (UTC).
ArgSpec time_arg(std::string name, const std::string& description) {
  return text_arg(std::move(name),
                  description + ": \"YYYY-MM-DD\" or \"YYYY-MM-DDTHH:MM:SSZ\" (UTC)");
}

/// The time argument `name` of a validated request in ms since the epoch; a bad_request naming
/// it when it is there but no UTC time.
std::optional<Error> read_time(const nlohmann::json& request, const char* name,
                               std::optional<std::int64_t>& out) {
  const auto it = request.find(name);
  if (it == request.end()) return std::nullopt;
  const auto ms = parse_utc_ms(it->get<std::string>());
  if (!ms) {
    return Error{ErrorCode::BadRequest,
                 std::string("field \"") + name + "\": " + it->dump().substr(0, 60) +
                     " is no UTC time; allowed: \"YYYY-MM-DD\" or \"YYYY-MM-DDTHH:MM:SS[.mmm]Z\"",
                 name};
  }
  out = ms;
  return std::nullopt;
}

/// `from` and `to` of a validated request, `from` before `to` when both are given.
std::optional<Error> read_range(const nlohmann::json& request, std::optional<std::int64_t>& from,
                                std::optional<std::int64_t>& to) {
  if (auto e = read_time(request, "from", from)) return e;
  if (auto e = read_time(request, "to", to)) return e;
  if (from && to && *from >= *to) {
    return Error{ErrorCode::BadRequest, "field \"from\" must be before \"to\"", "from"};
  }
  return std::nullopt;
}

/// What `history` and `trend` share: `from`, `to` and `floor` into `args`; a bad time refuses.
template <typename Args>
std::optional<Error> read_days_and_floor(const nlohmann::json& request, Args& args) {
  if (auto e = read_range(request, args.from_unix_ms, args.to_unix_ms)) return e;
  if (request.contains("floor")) args.floor = request.at("floor").get<int>();
  return std::nullopt;
}

}  // namespace

void add_record_commands(Dispatcher& dispatcher, Backend& backend) {
  Backend* b = &backend;
  dispatcher.add({"counters",
                  Access::Read,
                  {},
                  "the lift's lifetime counters and each floor's stopping error, kept across "
                  "restarts",
                  [b](const Call&, Responder done) { done(b->counters()); },
                  kEveryDriveKind});

  ArgSpec names;
  names.name = "names";
  names.type = ArgType::Any;
  names.required = true;
  names.description =
      "counters to set to zero: names as `counters` lists them, a prefix with \".*\" "
      "(\"faults.*\"), \"floors\" or \"all\"";
  dispatcher.add({"counters_reset",
                  Access::Control,
                  {names},
                  "set chosen counters to zero; the reset itself is recorded",
                  [b](const Call& call, Responder done) {
                    const nlohmann::json& list = call.request.at("names");
                    std::vector<std::string> chosen;
                    const bool strings =
                        list.is_array() && !list.empty() && list.size() <= 256 &&
                        std::all_of(list.begin(), list.end(),
                                    [](const nlohmann::json& n) { return n.is_string(); });
                    if (!strings) {
                      done(Result::fail(ErrorCode::BadRequest,
                                        "field \"names\": " + list.dump().substr(0, 60) +
                                            " is not allowed; allowed: an array of 1..256 "
                                            "counter names",
                                        "names"));
                      return;
                    }
                    for (const auto& n : list) chosen.push_back(n.get<std::string>());
                    done(b->reset_counters(chosen, "uid " + std::to_string(call.peer.uid) +
                                                       " pid " + std::to_string(call.peer.pid)));
                  },
                  kEveryDriveKind});

  dispatcher.add(
      {"history",
       Access::Read,
       {time_arg("from", "travels that started at or after this time"),
        time_arg("to", "travels that started before this time"),
        int_arg("floor", false, 0, kMaxFloorIndex, "travels from or to this floor"),
        choice_arg("outcome", false, {"arrived", "aborted"}, "how the travels ended"),
        text_arg("cause", "the end's cause (\"arrived\", \"link_down\", ...)"),
        int_arg("limit", false, 1, 10000, "travels returned at most, newest first (default 100)"),
        flag_arg("curves", "with each travel's curve where the record kept it")},
       "the travels of the lift's record, newest first",
       [b](const Call& call, Responder done) {
         HistoryArgs args;
         if (auto e = read_days_and_floor(call.request, args)) {
           done(Result::fail(e->code, e->message, e->field));
           return;
         }
         if (call.request.contains("outcome")) {
           args.outcome = call.request.at("outcome").get<std::string>();
         }
         if (call.request.contains("cause")) {
           args.cause = call.request.at("cause").get<std::string>();
         }
         args.limit = static_cast<std::size_t>(arg_or<std::int64_t>(call.request, "limit", 100));
         args.curves = arg_or<bool>(call.request, "curves", false);
         done(b->history(args));
       },
       kEveryDriveKind});

  dispatcher.add({"trend",
                  Access::Read,
                  {time_arg("from", "days from this time"), time_arg("to", "days before this time"),
                   int_arg("floor", false, 0, kMaxFloorIndex, "this floor only")},
                  "floor-to-floor time and stopping error per floor and day",
                  [b](const Call& call, Responder done) {
                    TrendArgs args;
                    if (auto e = read_days_and_floor(call.request, args)) {
                      done(Result::fail(e->code, e->message, e->field));
                      return;
                    }
                    done(b->trend(args));
                  },
                  kEveryDriveKind});
}

}  // namespace liftd::api
