// The io-thread side of a lift whose controller runs on a real-time thread of its own behind
// lock-free queues (DCP on the cycle runner, SCH001 on the CAN runner, USS on the USS runner),
// written once for every drive kind:
// the API backend's drive-neutral commands and `status` fields, the flight recorder's files (the
// API's `trace` with `save`, SIGUSR1), and the lift's start and stop, its io-thread poll and its
// service-stop wind-down. What only one drive has (its link and events, its status details,
// stats and trace) stays in the kind's lift (lib/dcp/host/dcp_lift.*,
// lib/sch001/host/hydraulic_lift.*, lib/uss/host/uss_lift.*).
//
// `Drive` names the parts of one drive kind (see DcpDrive, Sch001Drive, UssDrive):
//   Controller (a lift::ControllerCore: its CoreTypes give the Command, Reply, Event, Snapshot
//   and TravelKind; the commands every kind takes are lift's), Runner, Simulator (as DriveParts
//   names them); kFacts (a DriveFacts), travel_bit_names() (the names of the drive's bits in a
//   travel's curve), learn_leg_base_ms(config) (the run-time limit a learning leg's allowance is
//   added to); where the car can move with no travel of the controller's running (a drive that
//   still reports travel active), also car_moving(snapshot).
#pragma once

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <asio.hpp>

#include "api/backend.hpp"
#include "api/server.hpp"
#include "common/position_source.hpp"
#include "config/config.hpp"
#include "drive/drive.hpp"
#include "host/eta.hpp"
#include "host/host.hpp"
#include "host/learn_report.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "host/motion.hpp"
#include "host/record_feed.hpp"
#include "host/registry_entry.hpp"
#include "host/serial_device_report.hpp"
#include "host/trace_files.hpp"
#include "host/travel_log.hpp"
#include "lift/controller_core.hpp"
#include "lift/learning_travel.hpp"
#include "log/log.hpp"

namespace liftd::daemon {

/// A drive kind's controller, the runner of its real-time thread and its simulator: the types a
/// Drive description names first.
template <typename ControllerT, typename RunnerT, typename SimulatorT>
struct DriveParts {
  using Controller = ControllerT;
  using Runner = RunnerT;
  using Simulator = SimulatorT;
};

/// What the io side needs to know of a drive kind's lift besides its types.
struct DriveFacts {
  drive::Kind kind = drive::Kind::Dcp;
  /// The real-time thread as the journal and a failed reply name it ("cycle", "CAN").
  std::string_view thread;
  /// A command its thread has not answered this long after it was sent (a learning's longest
  /// run added) is failed: the thread stalled.
  std::chrono::nanoseconds reply_grace{};
  /// After a service stop forced the travel's end, how long the thread goes on sending the
  /// drive its stopped state before it is stopped.
  std::chrono::nanoseconds shutdown_grace{};
  /// The texts of its drive's faults (lift::DriveFaultTexts::of gives every fault's).
  const lift::DriveFaultTexts* fault_texts = nullptr;

  /// drive.kind, the journal's component and the daemon's component name ("dcp").
  constexpr std::string_view name() const noexcept {
    return drive::kKindNames[static_cast<std::size_t>(kind)];
  }
  /// The journal's event when the thread cannot start ("cycle_start_failed").
  std::string start_failed_event() const {
    std::string event(thread);
    std::transform(event.begin(), event.end(), event.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return event + "_start_failed";
  }
};

/// The types the controller of `Drive` works on (lift::ControllerCore::CoreTypes).
template <class Drive>
using CoreOf = typename Drive::Controller::CoreTypes;

/// api::Backend over a controller on a real-time thread: what every such drive answers alike.
/// A drive's backend adds status(), stats(), trace(), travel() and drive_reset().
template <typename Drive>
class ControllerBackend : public api::Backend {
 public:
  using Controller = typename Drive::Controller;
  using Runner = typename Drive::Runner;
  using Simulator = typename Drive::Simulator;

  /// `decoder`: the flight recorder files' decoded column (none: the bytes only).
  ControllerBackend(const config::Config& config, const config::Schema& schema,
                    Controller& controller, Runner& runner, PositionFeed* position_feed,
                    Simulator* sim, FlightRecorderFiles::DecoderSource decoder = {})
      : config_(config),
        schema_(schema),
        controller_(controller),
        runner_(runner),
        sim_(sim),
        inputs_(config, position_feed, sim != nullptr),
        flight_recorder_(runner.recorder(), default_runtime_dir(config),
                         static_cast<std::size_t>(config.rt.trace_files_kept),
                         std::string(Drive::kFacts.name()), std::move(decoder)),
        travel_log_(Drive::travel_bit_names(), floor_levels_mm(config)),
        record_(config, sim != nullptr, mono_now()),
        eta_times_(floor_levels_mm(config), eta_defaults(config)),
        mono_at_start_(mono_now()),
        wall_at_start_(std::chrono::system_clock::now()) {
    travel_log_.set_completion_listener([this](const RecordedTravel& t) { keep_travel(t); });
    preload_eta();
  }

  drive::Kind drive_kind() const override { return Drive::kFacts.kind; }
  nlohmann::json config() override { return config::to_json(config_, schema_); }
  void update_inputs(const api::InputUpdate& update, api::Responder done) override {
    done(inputs_.take(update, [this](const lift::Inputs& now) { send_inputs(now); }));
  }
  void stop(api::Responder done) override { send(lift::StopCommand{}, std::move(done)); }
  void relevel(api::Responder done) override { send(lift::RelevelCommand{}, std::move(done)); }
  void inspection(bool on, const std::string& direction, api::Responder done) override {
    lift::InspectionCommand cmd;
    cmd.on = on;
    cmd.direction = direction_of(direction);
    send(cmd, std::move(done));
  }
  void calls(const api::CallsArgs& args, api::Responder done) override {
    if (args.action == "list") {
      done(api::Result::ok({{"calls", calls_list(controller_.snapshot())}}));
      return;
    }
    using Op = lift::CallCommand::Op;
    lift::CallCommand cmd;
    cmd.op = args.action == "add"      ? Op::Add
             : args.action == "cancel" ? Op::Cancel
             : args.action == "insert" ? Op::Insert
                                       : Op::Set;
    const bool adds_stops = cmd.op != Op::Cancel && !(cmd.op == Op::Set && args.floors.empty());
    if (adds_stops) {
      // docs/api.md `calls`: a car out of service takes no stop, as it starts no travel (the
      // service stop keeps its own answer, the controller's).
      const std::string reason = this->status().out_of_service;
      if (!reason.empty() && reason != "stopping") {
        done(api::Result::fail(api::ErrorCode::NotReady,
                               "the car is out of service (" + reason + "): it takes no calls"));
        return;
      }
      note_travel_asked();
    }
    cmd.floor = static_cast<std::size_t>(args.floor.value_or(0));
    cmd.position = args.position;
    cmd.count = std::min(args.floors.size(), cmd.floors.size());
    for (std::size_t i = 0; i < cmd.count; ++i) {
      cmd.floors[i] = static_cast<std::uint8_t>(args.floors[i]);
    }
    send(lift::CallCommand{cmd}, std::move(done));
  }
  void sim(const api::SimRequest& request, api::Responder done) override {
    if (sim_ == nullptr) {
      api::Backend::sim(request, std::move(done));
      return;
    }
    done(sim_->apply(request, mono_now()));
  }
  /// The learning travel (lift::LearnCommand), answered when it ends: within the run-time
  /// limits of both legs through the whole shaft (lift::learn_longest from
  /// Drive::learn_leg_base_ms), and the grace of every reply.
  void learn(api::Responder done) override {
    std::int64_t bottom_mm = 0;
    std::int64_t top_mm = 0;
    if (!config_.floors.empty()) {
      bottom_mm = config_.floors.front().level_mm;
      top_mm = config_.floors.back().level_mm;
    }
    const auto longest = lift::learn_longest(Drive::learn_leg_base_ms(config_), bottom_mm, top_mm);
    (void)post_command<typename CoreOf<Drive>::Command>(
        controller_, pending_, lift::LearnCommand{}, std::move(done),
        longest + Drive::kFacts.reply_grace, Drive::kFacts.thread,
        [this](const typename CoreOf<Drive>::Reply&) {
          record_.learning_travel(mono_now());
          nlohmann::json result = learn_result_json(config_, controller_.learn_record());
          if (learn_listener_) learn_listener_(result);
          return api::Result::ok(std::move(result));
        });
  }
  /// Called with each learning travel's result (the lift reports it to the journal and watchers).
  void set_learn_listener(std::function<void(const nlohmann::json&)> listener) {
    learn_listener_ = std::move(listener);
  }
  /// `trace` with `save`: the runner's flight recorder to a file, as the DCP lift writes it.
  api::Result save_trace() override {
    return flight_recorder_.save_requested(std::chrono::steady_clock::now());
  }

  api::Result travels(std::size_t last) override {
    return api::Result::ok(
        travel_log_.to_json(last, [this](MonoTime at) { return wall_time(at); }));
  }
  /// A travel event of the controller: a finished or aborted travel ends its curve.
  template <typename TravelEvent>
  void record_travel_event(const TravelEvent& t, MonoTime at) {
    using Type = decltype(t.type);
    if (t.type != Type::Finished && t.type != Type::Aborted) return;
    travel_log_.end(at, travel_end_cause(t.type == Type::Aborted, lift::to_string(t.cause)));
  }

  /// A fault the controller raised, for the lift's record.
  void record_fault(lift::FaultCode code, MonoTime at) { record_.fault_raised(code, at); }

  api::Result counters() override { return record_.counters(); }
  api::Result reset_counters(const std::vector<std::string>& names,
                             const std::string& who) override {
    return record_.reset(names, who);
  }
  api::Result history(const api::HistoryArgs& args) override { return record_.history(args); }
  api::Result trend(const api::TrendArgs& args) override { return record_.trend(args); }

  /// `eta`: from the car's status (every kind's, so out of service means the same) and the
  /// travels the log measured (docs/api.md "Arrival times").
  api::Result eta(const api::EtaArgs& args) override {
    const auto floors = static_cast<int>(config_.floors.size());
    if (args.floor && *args.floor >= floors) {
      return api::Result::fail(api::ErrorCode::BadRequest,
                               "field \"floor\": " + std::to_string(*args.floor) +
                                   " is no floor; allowed: 0.." + std::to_string(floors - 1));
    }
    const api::StatusSnapshot s = status();
    if (args.position && *args.position > s.calls.size()) {
      return api::Result::fail(api::ErrorCode::BadRequest,
                               "field \"position\": " + std::to_string(*args.position) +
                                   " is beyond the calls queue; allowed: 0.." +
                                   std::to_string(s.calls.size()));
    }
    std::optional<std::size_t> position = args.position;
    bool target_first = false;  // the queue's first floor is the running travel's target
    EtaCar car;
    car.in_service = s.out_of_service.empty();
    car.reason = s.out_of_service;
    car.position_mm = s.position_mm;
    car.floor = s.floor;
    car.target = s.target_floor;
    car.calls = s.calls;
    const auto& log = travel_log_.travels();
    if (!log.empty() && log.back().ended) {
      car.since_arrival_s = std::chrono::duration<double>(mono_now() - log.back().end).count();
    }
    if (s.target_floor) {
      // A travel taken whose run the log has not seen start yet counts from now.
      car.travelling = true;
      if (!log.empty() && !log.back().ended && !log.back().samples.empty()) {
        car.elapsed_s = std::chrono::duration<double>(mono_now() - log.back().start).count();
        car.origin = travel_origin(log.back());
      } else if (s.position_mm) {
        car.origin = floor_near(floor_levels_mm(config_), *s.position_mm,
                                config_.travel.relevel_threshold_mm);
      }
      // The queue's first call stays queued until served: it is the running travel's target.
      // A position counts in the queue as `calls` lists it, where 0 and 1 both mean right after
      // that target (as `calls insert` puts it).
      if (!car.calls.empty() && car.calls.front() == *s.target_floor) {
        car.calls.erase(car.calls.begin());
        if (position && *position > 0) --*position;
        target_first = true;
      }
    }
    nlohmann::json answer = estimate_eta(eta_times_, car, {args.floor, position});
    // The answer's position counts as the question's did.
    nlohmann::json& with = answer["with"];
    if (target_first && with.is_object() && with["position"].is_number_integer()) {
      with["position"] = with["position"].get<std::size_t>() + 1;
    }
    return api::Result::ok(std::move(answer));
  }

  /// The serial device of a drive link on a serial line (serial_device_report.hpp), for `stats`.
  void set_serial_device(io::SerialDeviceInfo info) { serial_device_ = std::move(info); }

  /// Writes the flight recorder to `<runtime dir>/liftd-trace-<UTC time>.txt` and journals it
  /// with `why` (SIGUSR1).
  api::Result write_flight_recorder(std::string_view why) { return flight_recorder_.write(why); }

  /// Io thread: replies to their clients, requests the controller's thread never answered time
  /// out.
  virtual void poll(MonoTime now) {
    typename CoreOf<Drive>::Reply r;
    while (controller_.poll_reply(r)) pending_.answer(r);
    travel_log_.drain(controller_);  // before the events: a travel's end finds its samples
    expire_unanswered(now);
    record_.inputs(inputs_.current(), now);
    record_.tick(now);
  }
  /// A sample of the simulated machine's inputs (--simulate), sent on with the API's shaft
  /// signals (MachineInputs).
  void simulated_inputs(const lift::Inputs& sample) {
    inputs_.take_sample(sample, [this](const lift::Inputs& now) { send_inputs(now); });
  }
  bool send_shutdown(bool force) {
    return controller_.post(typename CoreOf<Drive>::Command{0, lift::ShutdownCommand{force}});
  }
  std::chrono::system_clock::time_point wall_time(MonoTime at) const {
    return wall_at_start_ +
           std::chrono::duration_cast<std::chrono::system_clock::duration>(at - mono_at_start_);
  }

 protected:
  /// A travel or a call was asked for: with the car at rest and nothing queued, the run that
  /// follows tells `eta` how long a car at rest takes from the request to its start.
  void note_travel_asked() {
    const auto s = controller_.snapshot();
    const auto& log = travel_log_.travels();
    const bool running = !log.empty() && !log.back().ended;
    asked_at_.reset();
    if (!s.target_floor && s.call_count == 0 && !running) asked_at_ = mono_now();
  }
  static void not_offered(api::Responder& done) {
    done(api::Result::fail(
        api::ErrorCode::NotOffered,
        "not offered by drive kind \"" + std::string(Drive::kFacts.name()) + "\""));
  }
  using Pending = PendingReplies<typename CoreOf<Drive>::Reply>;
  /// Posts a command; an ok reply answers through `complete` (none: reply_result).
  template <typename Body>
  void send(Body&& body, api::Responder done, typename Pending::Completion complete = {}) {
    (void)post_command<typename CoreOf<Drive>::Command>(
        controller_, pending_, std::forward<Body>(body), std::move(done), Drive::kFacts.reply_grace,
        Drive::kFacts.thread, std::move(complete));
  }
  /// Fails the requests the controller's thread did not answer in Drive::kFacts.reply_grace.
  void expire_unanswered(MonoTime now) {
    pending_.expire(now, "the " + std::string(Drive::kFacts.thread) +
                             " thread did not answer; see the journal");
  }
  /// The drive-neutral fields of `status` from the controller's snapshot, with the link as the
  /// drive reads it: faults and drive state, where the car is, the travel, the calls, status.rt.
  api::StatusSnapshot neutral_status(const typename CoreOf<Drive>::Snapshot& s,
                                     api::LinkState link) const {
    using TravelKind = typename CoreOf<Drive>::TravelKind;
    api::StatusSnapshot out;
    out.drive_kind = Drive::kFacts.kind;
    out.link = link;
    out.faults = active_faults(
        s.faults, s.fault_since,
        [](lift::FaultCode code) { return Drive::kFacts.fault_texts->of(code); },
        [this](MonoTime at) { return wall_time(at); });
    out.drive_state =
        drive::state_of(out.link == api::LinkState::Up, s.travel_kind != TravelKind::None,
                        !out.faults.empty(), s.drive_allows_travel);
    out.position_mm = s.position_mm;
    // docs/api.md: car.floor only while the car stands at a level, not while a travel passes one.
    if (s.travel_kind == TravelKind::None && s.floor) {
      out.floor = static_cast<int>(*s.floor);
      out.next_possible_stop = out.floor;
    } else if (s.next_possible_stop) {  // where a stop now would land the moving car
      out.next_possible_stop = static_cast<int>(*s.next_possible_stop);
    }
    out.travel_state = std::string(CoreOf<Drive>::Travel::kind_name(s.travel_kind));
    out.travel_direction = direction_name(s.direction);
    if (s.target_floor) out.target_floor = static_cast<int>(*s.target_floor);
    for (std::size_t i = 0; i < s.call_count; ++i) out.calls.push_back(s.calls[i]);
    out.rt = rt_info(runner_.thread_status(), config_.rt.priority);
    out.record = record_.status();
    out.doors = door_state(s.inputs);
    const auto& log = travel_log_.travels();
    out.motion =
        motion_phase(s.travel_kind != TravelKind::None, log.empty() ? nullptr : &log.back());
    out.out_of_service =
        out_of_service(s.shutting_down, !out.faults.empty(), s.inputs, s.learning, out.drive_state);
    return out;
  }

  /// The drive-neutral part of `stats`: the frames (or telegrams) the link sent and the steps its
  /// thread made, and what the controller's queues dropped; the kind adds its `details`.
  api::StatsSnapshot neutral_stats(std::uint64_t frames_sent, std::uint64_t cycles) const {
    api::StatsSnapshot out;
    out.drive_kind = Drive::kFacts.kind;
    out.frames_sent = frames_sent;
    out.cycles = cycles;
    out.dropped_events = controller_.dropped_events();
    out.dropped_travel_samples = controller_.dropped_travel_samples();
    return out;
  }
  /// `stats.<kind>.serial` of a drive on a serial line, once the lift read it.
  void add_serial_device(nlohmann::json& details) const {
    if (serial_device_) details["serial"] = serial_device_json(*serial_device_);
  }

  const config::Config& config_;
  const config::Schema& schema_;  ///< the configuration file's, for the `config` dump
  Controller& controller_;
  Runner& runner_;
  Simulator* sim_;
  MachineInputs inputs_;  ///< the API's and the simulated machine's inputs
  Pending pending_;
  /// The runner's recorder to files in the runtime directory.
  FlightRecorderFiles flight_recorder_;
  TravelLog travel_log_;  ///< the last travels and their curves (`travels`)
  std::optional<io::SerialDeviceInfo> serial_device_;  ///< set before the link's thread starts
  RecordFeed record_;  ///< the lift's record on the board's storage (`counters`, `history`)

 private:
  /// A travel the log completed, to the lift's record (with its curve where the record keeps
  /// curves). The floors are told within the relevelling threshold: a car farther off its level
  /// stands between floors.
  void keep_travel(const RecordedTravel& t) {
    learn_travel_time(t);
    const auto unix_ms = [this](MonoTime at) {
      return std::chrono::duration_cast<std::chrono::milliseconds>(wall_time(at).time_since_epoch())
          .count();
    };
    record_.travel(record_travel(t, floor_levels_mm(config_), config_.travel.relevel_threshold_mm,
                                 unix_ms(t.start), unix_ms(t.end),
                                 record_.wants_curves() ? travel_log_.curve_columns(t)
                                                        : nlohmann::json(nullptr)),
                   mono_now());
  }

  static EtaDefaults eta_defaults(const config::Config& c) {
    return {static_cast<double>(c.eta.speed_mm_s), static_cast<double>(c.eta.acceleration_mm_s2),
            c.eta.start_ms / 1000.0, c.eta.stop_ms / 1000.0};
  }
  /// The floor a travel started at (within the relevelling threshold), if any.
  std::optional<int> travel_origin(const RecordedTravel& t) const {
    if (t.samples.empty() || !t.samples.front().position_known) return std::nullopt;
    return floor_near(floor_levels_mm(config_), t.samples.front().position_mm,
                      config_.travel.relevel_threshold_mm);
  }
  /// `eta` after a restart rests on the travels the lift's record kept (docs/api.md "Arrival
  /// times"): the newest arrived ones, enough for every pair's window of the largest table.
  void preload_eta() {
    api::HistoryArgs newest;
    newest.outcome = "arrived";
    newest.limit = 2000;
    const api::Result kept = record_.history(newest);
    if (!kept.is_ok()) return;  // the record is off: its status says why
    const std::size_t taken =
        preload_travel_times(eta_times_, kept.value().value("travels", nlohmann::json::array()),
                             config_.travel.relevel_threshold_mm);
    if (taken == 0) return;
    log::event(log::Level::info, "travel", "eta_preloaded", {{"travels", std::to_string(taken)}},
               "eta: " + std::to_string(taken) + " floor-to-floor travels taken from the record");
  }
  /// A completed travel to `eta`'s times: a floor-to-floor travel of the lift's own (not a
  /// relevelling, an inspection or recall run, nor a learning travel's leg) that stood at its
  /// target; and the time the car stood at a queued stop before it (arrival to this start).
  void learn_travel_time(const RecordedTravel& t) {
    const bool queued_before = stop_from_.has_value();
    const MonoTime stood_from = stop_from_.value_or(MonoTime{});
    stop_from_.reset();
    const std::optional<MonoTime> asked = asked_at_;
    asked_at_.reset();
    if (t.cause != std::optional<std::string>("arrived") || !t.target_floor) return;
    const auto snapshot = controller_.snapshot();
    if (snapshot.learning || !eta_floor_to_floor(t.kind)) return;
    if (queued_before && t.start > stood_from && t.start - stood_from < std::chrono::seconds(60)) {
      eta_times_.stop(std::chrono::duration<double>(t.start - stood_from).count());
    }
    if (asked && t.start >= *asked && t.start - *asked < std::chrono::seconds(10)) {
      eta_times_.start(std::chrono::duration<double>(t.start - *asked).count());
    }
    // A stop follows when the car has another call queued at its arrival.
    if (snapshot.call_count > 0) stop_from_ = t.end;
    const auto from = travel_origin(t);
    if (!from || t.samples.empty() || !t.samples.back().position_known) return;
    const std::int64_t level = floor_levels_mm(config_).at(*t.target_floor);
    if (std::llabs(t.samples.back().position_mm - level) > config_.travel.relevel_threshold_mm) {
      return;
    }
    MeasuredTravel m;
    m.from = *from;
    m.to = static_cast<int>(*t.target_floor);
    m.duration_s = std::chrono::duration<double>(t.end - t.start).count();
    std::vector<double> speeds;
    for (const auto& sample : t.samples) {
      if (sample.speed_known) speeds.push_back(static_cast<double>(sample.speed_mm_s));
    }
    m.top_speed_mm_s = cruise_speed_mm_s(std::move(speeds));
    std::optional<MonoTime> moving_from;
    for (const auto& sample : t.samples) {
      if (!sample.speed_known) continue;
      const double v = std::abs(static_cast<double>(sample.speed_mm_s));
      if (!moving_from && v > 0.0) moving_from = sample.at;
      if (moving_from && m.top_speed_mm_s > 0.0 && v >= 0.9 * m.top_speed_mm_s) {
        m.acceleration_time_s = std::chrono::duration<double>(sample.at - *moving_from).count();
        break;
      }
    }
    eta_times_.travel(m);
  }

  void send_inputs(const lift::Inputs& inputs) {
    (void)controller_.post(typename CoreOf<Drive>::Command{0, lift::InputsCommand{inputs}});
  }

  TravelTimes eta_times_;  ///< `eta`'s measured travel and stop times
  /// The arrival of the last travel, when another call was queued then: the stop's start.
  std::optional<MonoTime> stop_from_;
  /// When a travel or call was asked for with the car at rest and nothing queued.
  std::optional<MonoTime> asked_at_;
  MonoTime mono_at_start_{};
  std::chrono::system_clock::time_point wall_at_start_{};
  std::function<void(const nlohmann::json&)> learn_listener_;
};

/// The lift as one piece over a controller on a real-time thread, registered with the daemon:
/// the simulator (--simulate), the controller, its runner, the backend and the API server. A
/// drive's lift makes the simulator, the controller and the runner in its constructor, then
/// calls register_parts(); its destructor calls shut_down().
template <typename Drive>
class ControllerLift : public LiftRunner {
 public:
  using Backend = ControllerBackend<Drive>;

  const std::string& socket_path() const override { return socket_path_; }

 protected:
  /// `continuous`: the status details that change while moving, published at the state rate.
  ControllerLift(Host& daemon, const config::Config& config, bool simulate,
                 std::vector<std::string> continuous = {})
      : daemon_(daemon),
        config_(config),
        simulate_(simulate),
        socket_path_(config.api.socket),
        wake_(daemon.io(), kFallbackPoll),
        publisher_(config.api.state_rate_hz, std::move(continuous)),
        wind_down_(
            daemon, [this](bool force) { return backend_->send_shutdown(force); },
            kShutdownDeadline, Drive::kFacts.shutdown_grace) {}

  /// The position the API's `inputs` carry (position.source "api"), made as the car's position.
  const PositionSource& make_position_feed() {
    position_feed_ =
        std::make_unique<PositionFeed>(std::chrono::milliseconds(config_.inputs.timeout_ms));
    return *position_feed_;
  }
  /// The feed the backend hands the API's positions: for position.source "api" only.
  PositionFeed* api_position_feed() const {
    return config_.position.source == config::PositionSource::api ? position_feed_.get() : nullptr;
  }

  /// Once the simulator, the controller and the runner are made: the API server over `backend`,
  /// the daemon's components (the simulator, the thread as Drive::kFacts.name(), the API), the
  /// watchdog probe and the status line while running: "simulated `lift` running; API on ..."
  /// under --simulate, else "`link` starting on `endpoint`".
  void register_parts(std::unique_ptr<Backend> backend, std::string_view lift,
                      std::string_view link, std::string_view endpoint) {
    backend_ = std::move(backend);
    runner_->set_notify_fd(wake_.fd());  // its news wakes poll() at once
    server_ = std::make_unique<api::Server>(daemon_.io(), *backend_, api_server_config(config_),
                                            api_log_sink());
    backend_->set_learn_listener(
        [this](const nlohmann::json& result) { report_learn(*server_, result); });
    daemon_.add_drive_commands(server_->dispatcher(), *backend_);
    if (sim_) {
      daemon_.add_component({"sim", [this] { return sim_->start(); }, [this] { sim_->stop(); }});
    }
    daemon_.add_component({std::string(Drive::kFacts.name()), [this] { return start_runner(); },
                           [this] { stop_runner(); },
                           [this](std::function<void()> done) { wind_down(std::move(done)); }});
    register_api(daemon_, *server_, socket_path_);
    daemon_.set_dump_handler([this] { (void)backend_->write_flight_recorder("SIGUSR1"); });
    daemon_.set_progress_probe(progress_probe([this] { return runner_->progress(); }));
    daemon_.set_running_status(
        simulate_ ? "simulated " + std::string(lift) + " running; API on " + socket_path_
                  : std::string(link) + " starting on " + std::string(endpoint));
  }

  /// Stops the API, the thread (journalling its last events) and the simulator, and frees the
  /// parts in the reverse order of their making: called by the drive's lift's destructor, while
  /// its handle_event() and the parts it made first (the USS master, the CAN encoder) are there.
  void shut_down() {
    if (server_) server_->stop();
    stop_runner();
    if (sim_) sim_->stop();
    server_.reset();
    backend_.reset();
    runner_.reset();
    controller_.reset();
  }

  /// Before the thread starts (the hydraulic lift checks its CAN interface; a drive on a serial
  /// line calls prepare_serial_device()).
  virtual void before_start() {}
  /// The serial device `device` of the drive link: journalled with its driver and settings, a USB
  /// adapter's latency timer set to 1 ms where liftd may (not under --simulate: a pty), and
  /// handed to the backend for `stats`.
  void prepare_serial_device(const std::string& device) {
    backend_->set_serial_device(simulate_
                                    ? io::query_serial_device(device)
                                    : daemon::prepare_serial_device(device, Drive::kFacts.name()));
  }
  /// Journals the thread's link once it runs.
  virtual void journal_started() = 0;
  /// An event only this drive kind reports (report_lift_event() took every lift's already).
  virtual void handle_event(const typename CoreOf<Drive>::Event& event) = 0;
  /// Every poll, after the controller's events: what only this drive watches.
  virtual void after_events(MonoTime) {}
  /// An event of the runner's own (its port, its timing), where it has them.
  virtual void handle_runner_event(const rt::CycleEvent& event) { journal_port_event(event); }

  /// docs/api.md `travel` events drive_fault and drive_fault_cleared: a DCP drive's travel
  /// events carry its S3 edges themselves (DCP 9.1.6); on the other kinds they are the edges of
  /// the drive fault (the SCH001 card's ERR, the USS status word's fault), with the travel that
  /// runs, if any.
  void report_drive_fault_edge(bool raised) {
    using TravelEvent = decltype(std::declval<typename CoreOf<Drive>::Event>().travel);
    if constexpr (!requires(const TravelEvent& t) { t.target_mm; }) {
      const auto s = controller_->snapshot();
      const auto floors = controller_->floors_mm();
      std::optional<std::int64_t> target_mm;
      if (s.target_floor && *s.target_floor < floors.size()) target_mm = floors[*s.target_floor];
      const bool running = s.travel_kind != typename CoreOf<Drive>::TravelKind{};
      report_travel(*server_, raised ? "drive_fault" : "drive_fault_cleared",
                    running ? CoreOf<Drive>::Travel::kind_name(s.travel_kind) : "none",
                    raised ? lift::Cause::DriveFault : lift::Cause::None, false, target_mm,
                    s.position_mm);
    }
  }
  /// Journals and publishes the events every such controller reports alike: a travel, a fault
  /// raised or cleared, a served call, dropped calls. False for a kind's own event.
  bool report_lift_event(const typename CoreOf<Drive>::Event& event) {
    using Kind = typename CoreOf<Drive>::Event::Kind;
    switch (event.kind) {
      case Kind::Travel:
        backend_->record_travel_event(event.travel, event.at);
        report_travel(*server_, event.travel, *controller_);
        break;
      case Kind::FaultRaised:
      case Kind::FaultCleared:
        report_fault(*server_, event.fault, Drive::kFacts.fault_texts->of(event.fault),
                     event.kind == Kind::FaultRaised);
        // The frames that led to a link fault are what a technician needs first: the recorder
        // goes to a file at once, on every kind (docs/operations.md "The flight recorder").
        if (event.kind == Kind::FaultRaised) backend_->record_fault(event.fault, event.at);
        if (event.kind == Kind::FaultRaised && event.fault == lift::FaultCode::LinkFault) {
          (void)backend_->write_flight_recorder("link fault");
        }
        if (event.fault == lift::FaultCode::DriveFault) {
          report_drive_fault_edge(event.kind == Kind::FaultRaised);
        }
        break;
      case Kind::CallServed:
        report_call_served(*server_, event.floor);
        break;
      case Kind::CallsDropped:
        report_calls_dropped(*server_, event.dropped, event.cause);
        break;
      default:  // the drive's own events: handle_event()
        return false;
    }
    return true;
  }

  Host& daemon_;
  const config::Config& config_;
  bool simulate_;
  std::unique_ptr<typename Drive::Simulator> sim_;
  std::unique_ptr<PositionFeed> position_feed_;
  std::unique_ptr<typename Drive::Controller> controller_;
  std::unique_ptr<typename Drive::Runner> runner_;
  std::unique_ptr<Backend> backend_;
  std::unique_ptr<api::Server> server_;

 private:
  bool start_runner() {
    before_start();
    const int error = runner_->start();
    if (error != 0) {
      log::event(log::Level::error, Drive::kFacts.name(), Drive::kFacts.start_failed_event(),
                 {{"errno", std::to_string(error)}},
                 "cannot start the " + std::string(Drive::kFacts.thread) +
                     " thread: " + std::strerror(error));
      return false;
    }
    if (!accept_rt_thread(config_, runner_->thread_status(), simulate_, Drive::kFacts.thread)) {
      runner_->stop();
      return false;
    }
    journal_started();
    wake_.start([this] { poll(); });
    return true;
  }

  void stop_runner() {
    if (!wake_.running()) return;
    wake_.stop();
    runner_->stop();
    poll();  // the last events
  }

  /// The io thread's step whenever the thread has news (and every kFallbackPoll): the simulated
  /// machine's inputs every kSimInputsPeriod, the controller's replies and events (and the
  /// runner's own, where it has them), the `state` event, the wind-down's check.
  void poll() {
    const MonoTime now = mono_now();
    if (sim_ && now - last_sim_inputs_ >= kSimInputsPeriod) {
      backend_->simulated_inputs(sim_->inputs(now));
      last_sim_inputs_ = now;
      sim_->log_violations();
    }
    backend_->poll(now);
    if constexpr (requires(typename Drive::Runner & r, rt::CycleEvent & e) { r.poll_event(e); }) {
      rt::CycleEvent cycle_event;
      while (runner_->poll_event(cycle_event)) handle_runner_event(cycle_event);
    }
    typename CoreOf<Drive>::Event event;
    while (controller_->poll_event(event)) {
      if (!report_lift_event(event)) handle_event(event);
    }
    after_events(now);
    publisher_.publish(*server_, backend_->status(), now);
    const typename CoreOf<Drive>::Snapshot rest = controller_->snapshot();
    wind_down_.check({rest.shutting_down, rest.quiesced, rest.floor, rest.position_mm}, now);
  }

  void wind_down(std::function<void()> done) {
    if (!wake_.running()) {
      done();
      return;
    }
    const typename CoreOf<Drive>::Snapshot s = controller_->snapshot();
    bool moving = s.travel_kind != CoreOf<Drive>::TravelKind::None;
    if constexpr (requires { Drive::car_moving(s); }) moving = Drive::car_moving(s);
    // Every client, watching or not, hears that liftd is going and why: the last line before
    // the connection closes (docs/api.md `stopping`).
    server_->announce("stopping",
                      {{"reason", std::string(daemon_.stop_reason())}, {"car_moving", moving}});
    wind_down_.start(std::move(done), moving, s.target_floor, mono_now());
  }

  std::string socket_path_;
  ThreadWake wake_;
  StatePublisher publisher_;
  MonoTime last_sim_inputs_{};
  WindDown wind_down_;
};

}  // namespace liftd::daemon

namespace liftd::host {

template <class Lift>
std::unique_ptr<daemon::LiftRunner> make_lift(daemon::Host& host, const config::Config& config,
                                              bool simulate) {
  return std::make_unique<Lift>(host, config, simulate);
}

}  // namespace liftd::host
