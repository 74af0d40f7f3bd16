// The USS lift's API backend: status, stats, trace, travels and the USS commands (PKW, mirror).
#include "uss/config/section.hpp"
#include "uss/host/uss_lift.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "api/commands.hpp"
#include "log/log.hpp"
#include "uss/host/sim_actions.hpp"
#include "uss/timing.hpp"

namespace liftd::daemon {
namespace {

using api::Result;

/// {"on": true, "no_off2": true, ...}: the bits 0..10 of a control or status word by name.
nlohmann::json word_bits(std::uint16_t word, const std::array<std::string_view, 11>& names) {
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t bit = 0; bit < names.size(); ++bit) {
    out[std::string(names[bit])] = (word & (1U << bit)) != 0;
  }
  return out;
}

}  // namespace

api::StatusSnapshot UssBackend::status() {
  const uss::ControllerSnapshot s = controller_.snapshot();
  const api::LinkState link = !s.port_up || !s.drive_heard
                                  ? (s.drive_heard ? api::LinkState::Fault : api::LinkState::Down)
                                  : (s.link_ok ? api::LinkState::Up : api::LinkState::Fault);
  api::StatusSnapshot out = neutral_status(s, link);
  nlohmann::json d = nlohmann::json::object();
  d["drive_address"] = s.drive_address;
  d["profile_state"] = std::string(uss::to_string(s.drive_state));
  d["wish"] = std::string(uss::to_string(s.wish));
  d["supervision"] = std::string(uss::to_string(s.supervision));
  d["control_word"] = s.stw_sent;
  d["status_word"] = s.zsw;
  d["control_bits"] = word_bits(s.stw_sent, uss::kControlWordBitNames);
  d["status_bits"] = word_bits(s.zsw, uss::kStatusWordBitNames);
  d["setpoint"] = {{"raw", s.setpoint_raw}, {"percent", s.setpoint_percent}};
  d["actual"] = {{"raw", s.actual_raw}, {"percent", std::round(s.actual_percent * 10.0) / 10.0}};
  d["phase"] = std::string(uss::to_string(s.phase));
  d["speed"] = std::string(uss::to_string(s.speed));
  nlohmann::json slaves = nlohmann::json::array();
  for (std::size_t i = 0; i < s.slave_count; ++i) {
    const uss::SlaveSnapshot& sl = s.slaves[i];
    slaves.push_back({{"address", sl.address},
                      {"heard", sl.heard},
                      {"responding", sl.responding},
                      {"pkw_busy", sl.pkw_busy}});
  }
  d["slaves"] = std::move(slaves);
  d["line_echo"] = line_echo_json(runner_.config().echo, runner_.echo_state());
  out.details = std::move(d);
  out.brake_open = s.brake_open;
  out.contactors_on = s.contactors_on;
  return out;
}

api::StatsSnapshot UssBackend::stats() {
  const uss::ControllerSnapshot s = controller_.snapshot();
  const uss::UssRunnerStats r = runner_.stats();
  api::StatsSnapshot out = neutral_stats(r.counters.exchanges, r.counters.cycles);
  nlohmann::json rx = {{"good", s.rx.good},
                       {"rejected", s.rx.rejected},
                       {"framing", s.rx.framing},
                       {"overrun", s.rx.overrun},
                       {"parity", s.rx.parity},
                       {"no_stx", s.rx.no_stx},
                       {"residual_time", s.rx.residual_time},
                       {"bcc", s.rx.bcc},
                       {"lge", s.rx.lge},
                       {"reply_timeout", s.rx.reply_timeout},
                       {"error_word", s.rx.error_word}};
  nlohmann::json slaves = nlohmann::json::array();
  for (std::size_t i = 0; i < s.slave_count; ++i) {
    const uss::SlaveSnapshot& sl = s.slaves[i];
    nlohmann::json pzd = nlohmann::json::array();
    for (std::size_t w = 0; w < sl.pzd_in_count; ++w) pzd.push_back(sl.pzd_in[w]);
    slaves.push_back({{"address", sl.address},
                      {"good", sl.good},
                      {"failures", sl.failures},
                      {"consecutive_failures", sl.consecutive_failures},
                      {"pzd_in", std::move(pzd)}});
  }
  const auto us = [](std::chrono::nanoseconds t) {
    return std::chrono::duration_cast<std::chrono::microseconds>(t).count();
  };
  // The bus's own figures (docs/api.md `stats`); a reply timeout and a BCC error are counted in
  // `receive` (USS A 5.2.3), not twice.
  out.details = {{"baud", uss_section(config_).baud},
                 {"expected_cycle_time_us", us(s.expected_cycle_time)},
                 {"last_cycle_time_us", us(s.last_cycle_time)},
                 {"cycle_time_p99_us", r.cycle_time.percentile_us(0.99)},
                 {"replies_good", r.counters.good_replies},
                 {"replies_rejected", r.counters.bad_replies},
                 {"port_losses", r.counters.port_losses},
                 {"max_lateness_us", static_cast<std::uint64_t>(r.wake_lateness.max_us())},
                 {"lateness_p99_us", r.wake_lateness.percentile_us(0.99)},
                 {"reply_p99_us", r.reply_time.percentile_us(0.99)},
                 {"line_errors", r.counters.line_errors},
                 {"echo_collisions", r.counters.echo_collisions},
                 {"receive", std::move(rx)},
                 {"slaves", std::move(slaves)}};
  add_serial_device(out.details);
  return out;
}

std::vector<api::TraceEntry> UssBackend::trace(std::size_t max_entries) {
  // Each telegram of ours with the reply to it (none for a broadcast or a silent slave).
  return trace_exchanges(runner_.recorder().copy(), max_entries, {.we_answer = false});
}

std::optional<uss::PkwLength> UssBackend::pkw_length(std::uint8_t address) const {
  for (const auto& s : master_.config().slaves) {
    if (s.address == address) return s.pkw;
  }
  return std::nullopt;
}

api::Result UssBackend::parameter_result(const ParameterContext& context,
                                         const uss::PkwResult& r) const {
  const std::string slave = "slave " + std::to_string(context.address);
  switch (r.outcome) {
    case uss::PkwResult::Outcome::Done:
      break;
    case uss::PkwResult::Outcome::Error:
      // USS C 4.2.1.1: reply id 7, the error number in the PWE.
      return Result::fail(api::ErrorCode::BadRequest,
                          slave + " refused the request: error " + std::to_string(r.error_number) +
                              " (" + std::string(uss::error_text(r.error_number)) + ")");
    case uss::PkwResult::Outcome::NoAuthority:
      return Result::fail(api::ErrorCode::NotReady,
                          slave +
                              " gives the master no parameter authority (reply id 8): set "
                              "its parameter authority to this interface");
    case uss::PkwResult::Outcome::Unanswered:
      return Result::fail(api::ErrorCode::NotReady,
                          "no matching reply from " + slave + " after " +
                              std::to_string(uss_section(config_).pkw_repeat_limit) +
                              " polls (uss.pkw_repeat_limit)");
  }
  const uss::Pkw& reply = r.reply;
  nlohmann::json out = {
      {"address", context.address},
      {"pnu", reply.pnu},
      {"target", std::string(kParameterTargets[static_cast<std::size_t>(context.args.target)])},
      {"index", context.args.index},
      {"reply", std::string(uss::reply_name(reply.id))}};
  nlohmann::json words = nlohmann::json::array();
  for (std::uint16_t w : reply.pwe_words()) words.push_back(w);
  out["words"] = std::move(words);
  if (reply.id == uss::reply::kText) {
    // USS C 4.2.2: two characters per PWE word, high byte first.
    std::string text;
    for (std::uint16_t w : reply.pwe_words()) {
      for (std::uint8_t c : {static_cast<std::uint8_t>(w >> 8), static_cast<std::uint8_t>(w)}) {
        if (c != 0) text += static_cast<char>(c);
      }
    }
    out["text"] = text;
  } else {
    const uss::PkwWidth width = uss::reply_width(reply.id);
    out["width"] = width == uss::PkwWidth::Dword ? "dword" : "word";
    out["value"] = uss::value(reply, context.length, width);
  }
  return Result::ok(std::move(out));
}

void UssBackend::travel(const api::TravelArgs& args, api::Responder done) {
  note_travel_asked();
  uss::TravelCommand cmd;
  cmd.floor = static_cast<std::size_t>(args.floor);
  if (args.speed) {
    const auto speed = uss::parse_speed(*args.speed);
    if (!speed || uss_section(config_).speeds.count(*args.speed) == 0) {
      done(Result::fail(api::ErrorCode::BadRequest,
                        "speed " + *args.speed + " has no setpoint in uss.speeds", "speed"));
      return;
    }
    cmd.speed = *speed;
  } else {
    // The fastest travelling speed of the installation (travel.dcp3_speed_count, fastest first).
    cmd.speed = *uss::parse_speed(config::dcp3_speeds(config_.travel.dcp3_speed_count).front());
  }
  send(cmd, std::move(done));
}

void UssBackend::drive_reset(api::Responder done) {
  // The result has the shape of the DCP drive's reset: {"reset": true, "detail": ...}.
  send(uss::DriveResetCommand{}, [done = std::move(done)](Result r) mutable {
    if (!r.is_ok()) {
      done(std::move(r));
      return;
    }
    nlohmann::json v = r.value();
    v["reset"] = true;
    if (!v.contains("detail")) {
      v["detail"] = "fault acknowledged: control word bit 7 rising edge (USS C 5.2.1)";
    }
    done(Result::ok(std::move(v)));
  });
}

void UssBackend::parameter(const ParameterArgs& args, api::Responder done) {
  const auto address =
      static_cast<std::uint8_t>(args.address.value_or(uss_section(config_).drive_address));
  const auto length = pkw_length(address);
  if (!length) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(address) +
                          " is not on this bus: it is neither uss.drive_address nor in uss.slaves",
                      "address"));
    return;
  }
  if (*length == uss::PkwLength::None) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(address) +
                          " has no PKW area (pkw \"0\", USS C 4.1): its parameters cannot be "
                          "reached",
                      "address"));
    return;
  }
  const uss::PkwTarget target = args.target == ParameterTarget::Array ? uss::PkwTarget::ArrayElement
                                : args.target == ParameterTarget::Description
                                    ? uss::PkwTarget::Description
                                : args.target == ParameterTarget::Text ? uss::PkwTarget::Text
                                                                       : uss::PkwTarget::Value;
  const uss::PkwWidth width = args.dword ? uss::PkwWidth::Dword : uss::PkwWidth::Word;
  uss::Pkw request;
  request.pnu = static_cast<std::uint16_t>(args.pnu);
  request.ind = uss::make_ind(target, static_cast<std::uint8_t>(args.index));
  if (args.write) {
    const auto id = uss::write_request_id(target, width, args.eeprom);
    if (!id) {
      done(Result::fail(api::ErrorCode::BadRequest, "USS has no such change request (C 4.2.1.1)",
                        "target"));
      return;
    }
    // USS C 4.1.1: three PKW words carry one PWE word; a double word needs four (or variable).
    if (width == uss::PkwWidth::Dword && *length == uss::PkwLength::Three) {
      done(Result::fail(api::ErrorCode::BadRequest,
                        "slave " + std::to_string(address) +
                            " has a PKW area of 3 words: one PWE word, no room for a double word",
                        "width"));
      return;
    }
    request.id = *id;
    uss::set_value(request, *length, width, static_cast<std::uint32_t>(args.value));
  } else {
    request.id = *uss::read_request_id(target);
  }
  uss::ParameterCommand cmd;
  cmd.address = address;
  cmd.request = request;
  const ParameterContext context{args, address, *length};
  send(cmd, std::move(done), [this, context](const uss::CommandReply& r) {
    return r.pkw ? parameter_result(context, *r.pkw) : reply_result(r);
  });
}

void UssBackend::mirror(std::optional<int> address, api::Responder done) {
  const auto a = static_cast<std::uint8_t>(address.value_or(uss_section(config_).drive_address));
  if (!pkw_length(a)) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(a) +
                          " is not on this bus: it is neither uss.drive_address nor in uss.slaves",
                      "address"));
    return;
  }
  send(uss::MirrorCommand{a}, std::move(done), [](const uss::CommandReply& r) {
    if (!r.mirror) return reply_result(r);
    const auto us =
        std::chrono::duration_cast<std::chrono::microseconds>(r.mirror->round_trip).count();
    return r.mirror->ok
               ? Result::ok({{"address", r.mirror->address}, {"ok", true}, {"round_trip_us", us}})
               : Result::fail(api::ErrorCode::Fault, "the mirror telegram to slave " +
                                                         std::to_string(r.mirror->address) +
                                                         " did not come back unchanged in time "
                                                         "(USS A 5.3)");
  });
}

}  // namespace liftd::daemon
