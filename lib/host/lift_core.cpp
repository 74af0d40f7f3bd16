#include "host/lift_core.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "host/catalog_keys.hpp"
#include "host/lift_common.hpp"
#include "log/log.hpp"

namespace liftd::daemon {

void StatePublisher::publish(api::Server& server, api::StatusSnapshot status, MonoTime now) {
  if (last_ && status == *last_) return;
  // Position alone changes often while moving: rate-limited; anything else goes out at once.
  api::StatusSnapshot without_position = status;
  if (last_) {
    without_position.position_mm = last_->position_mm;
    for (const std::string& key : continuous_) {
      if (without_position.details->contains(key) && last_->details->contains(key)) {
        without_position.details.edit()[key] = last_->details->at(key);
      }
    }
  }
  const bool discrete = !last_ || !(without_position == *last_);
  if (!discrete && now - last_publish_ < interval_) return;
  server.publish("state", api::to_json(status));
  last_ = std::move(status);
  last_publish_ = now;
}

ThreadWake::ThreadWake(asio::io_context& io, std::chrono::nanoseconds fallback)
    : fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)),
      news_(io),
      fallback_timer_(io),
      fallback_(fallback) {
  if (fd_ < 0) {
    throw std::runtime_error(std::string("cannot create the io thread's wake-up eventfd: ") +
                             std::strerror(errno));
  }
  news_.assign(fd_);
}

void ThreadWake::start(std::function<void()> poll) {
  poll_ = std::move(poll);
  running_ = true;
  wait_for_news();
  arm_fallback();
}

void ThreadWake::stop() {
  running_ = false;
  news_.cancel();
  fallback_timer_.cancel();
}

void ThreadWake::wait_for_news() {
  news_.async_wait(asio::posix::stream_descriptor::wait_read, [this](const asio::error_code& ec) {
    if (ec || !running_) return;
    std::uint64_t count = 0;
    // Resets the eventfd; EAGAIN (nothing since the last read) is harmless.
    [[maybe_unused]] const ssize_t n = ::read(fd_, &count, sizeof count);
    poll_();
    wait_for_news();
  });
}

void ThreadWake::arm_fallback() {
  fallback_timer_.expires_after(fallback_);
  fallback_timer_.async_wait([this](const asio::error_code& ec) {
    if (ec || !running_) return;
    poll_();
    arm_fallback();
  });
}

void WindDown::start(std::function<void()> done, bool moving,
                     std::optional<std::size_t> target_floor, MonoTime now) {
  done_ = std::move(done);
  until_ = now + deadline_;
  forced_ = false;
  if (moving) {
    log::event(log::Level::info, "travel", "shutdown_stopping_travel",
               {{"target_floor", target_floor ? std::to_string(*target_floor) : "none"}},
               "stopping: bringing the car to rest at the next possible floor before exit");
    daemon_.report_status("stopping: bringing the car to rest before exit");
  }
  (void)send_shutdown_(false);
}

void WindDown::check(const RestFacts& facts, MonoTime now) {
  if (!done_) return;
  if (!facts.shutting_down && !forced_) (void)send_shutdown_(false);  // the queue was full
  if (!facts.quiesced && now < until_) return;
  if (!facts.quiesced && !forced_) {
    forced_ = true;
    until_ = now + grace_;
    (void)send_shutdown_(true);
    log::event(log::Level::error, "travel", "shutdown_forced", {},
               "stopping: the car did not come to rest in time; every travel signal dropped");
    return;
  }
  const std::string where =
      facts.floor ? "at floor " + std::to_string(*facts.floor)
                  : (facts.position_mm ? "at " + std::to_string(*facts.position_mm) + " mm" : "");
  log::event(log::Level::info, "travel", "shutdown_at_rest",
             {{"floor", facts.floor ? std::to_string(*facts.floor) : "none"}},
             "stopping: car at rest " + where + ", no travel signal");
  daemon_.report_status("stopping: car at rest " + where);
  auto done = std::move(done_);
  done_ = nullptr;
  done();
}

api::RtInfo rt_info(const rt::RtThreadStatus& status, int priority) {
  api::RtInfo out;
  out.realtime = status.realtime;
  out.policy = status.realtime ? "SCHED_FIFO" : "SCHED_OTHER";
  out.priority = status.realtime ? priority : 0;
  out.memory_locked = status.memory_locked;
  return out;
}

std::optional<std::string> direction_name(lift::Direction direction) {
  switch (direction) {
    case lift::Direction::Up:
      return "up";
    case lift::Direction::Down:
      return "down";
    case lift::Direction::None:
      break;
  }
  return std::nullopt;
}

void report_fault(api::Server& server, lift::FaultCode code, std::string_view text, bool active) {
  const std::string name(lift::fault_code_name(code));
  log::event(active ? log::Level::warn : log::Level::info, "safety",
             active ? "fault_raised" : "fault_cleared", {{"code", name}},
             std::string(active ? "fault: " : "fault cleared: ") + std::string(text),
             fault_catalog_key(code, active));
  server.publish("fault", {{"code", name}, {"text", std::string(text)}, {"active", active}});
}

void report_travel(api::Server& server, std::string_view type, std::string_view kind,
                   lift::Cause cause, bool aborted, std::optional<std::int64_t> target_mm,
                   std::optional<std::int64_t> position_mm) {
  const std::string_view cause_name =
      cause == lift::Cause::None ? std::string_view{} : lift::to_string(cause);
  std::string text = "travel " + std::string(type) + " (" + std::string(kind) + ")";
  log::Fields fields{{"kind", std::string(kind)}};
  if (aborted) {
    text += ": " + std::string(cause_name);
    fields.push_back({"cause", std::string(cause_name)});
  }
  if (position_mm) {
    text += " at " + std::to_string(*position_mm) + " mm";
    fields.push_back({"position_mm", std::to_string(*position_mm)});
  }
  log::event(aborted ? log::Level::warn : log::Level::info, "travel", "travel_" + std::string(type),
             fields, text, aborted ? std::optional(abort_catalog_key(cause)) : std::nullopt);
  server.publish(
      "travel",
      {{"event", std::string(type)},
       {"kind", std::string(kind)},
       {"cause", cause_name.empty() ? nlohmann::json(nullptr) : nlohmann::json(cause_name)},
       {"target_mm", target_mm ? nlohmann::json(*target_mm) : nlohmann::json(nullptr)},
       {"position_mm", position_mm ? nlohmann::json(*position_mm) : nlohmann::json(nullptr)}});
}

std::optional<std::string> door_state(const lift::Inputs& inputs) {
  if (!inputs.valid) return std::nullopt;
  if (inputs.door_reversal) return "reopening";
  if (inputs.doors_locked) return "locked";
  if (inputs.doors_closed) return "closed";
  return "open";
}

std::string out_of_service(bool stopping, bool faulted, const lift::Inputs& inputs, bool learning,
                           drive::State drive_state) {
  if (stopping) return "stopping";
  if (faulted) return "fault";
  if (inputs.inspection) return "inspection";
  if (inputs.recall) return "recall";
  if (learning) return "learning";
  if (drive_state == drive::State::Offline || drive_state == drive::State::NotReady) {
    return "not_ready";
  }
  return {};
}

void report_calls_dropped(api::Server& server, const lift::DroppedCalls& dropped,
                          lift::Cause cause) {
  nlohmann::json floors = nlohmann::json::array();
  std::string list;
  for (std::size_t floor = 0; floor < dropped.floors.size(); ++floor) {
    if (!dropped.floors.test(floor)) continue;
    floors.push_back(floor);
    list += (list.empty() ? "" : " ") + std::to_string(floor);
  }
  const std::string why(lift::to_string(cause));
  log::event(log::Level::info, "travel", "calls_dropped", {{"floors", list}, {"cause", why}},
             "calls dropped (" + why + "): floors " + list);
  server.publish("calls_dropped", {{"floors", floors}, {"cause", why}});
}

void report_call_served(api::Server& server, std::size_t floor) {
  log::event(log::Level::info, "travel", "call_served", {{"floor", std::to_string(floor)}},
             "call served: floor " + std::to_string(floor));
  server.publish("call_served", {{"floor", floor}});
}

lift::Direction direction_of(std::string_view name) noexcept {
  return name == "up"     ? lift::Direction::Up
         : name == "down" ? lift::Direction::Down
                          : lift::Direction::None;
}

void register_api(Host& daemon, api::Server& server, const std::string& socket_path) {
  api::Server* s = &server;
  daemon.add_component({"api",
                        [s, socket_path] {
                          try {
                            s->start();
                          } catch (const std::exception& e) {
                            log::event(log::Level::error, "api", "api_start_failed",
                                       {{"socket", socket_path}}, e.what());
                            return false;
                          }
                          return true;
                        },
                        [s] { s->stop(); }});
  daemon.set_config_applier([s](const config::Config& next) {
    try {
      s->reconfigure(api_reload_config(next));
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  });
}

std::function<bool()> progress_probe(std::function<std::uint64_t()> progress) {
  return [progress = std::move(progress), last = std::uint64_t{0}]() mutable {
    const std::uint64_t p = progress();
    const bool advanced = p != last;
    last = p;
    return advanced;
  };
}

bool accept_rt_thread(const config::Config& config, const rt::RtThreadStatus& status, bool simulate,
                      std::string_view thread) {
  if (config.rt.require_realtime && !simulate && !status.realtime) {
    log::event(log::Level::error, "rt", "realtime_refused", {},
               "rt.require_realtime is true but the " + std::string(thread) +
                   " thread runs without real time: " + status.describe());
    return false;
  }
  if (const std::string line = status.describe(); !line.empty()) {
    log::event(log::Level::warn, "rt", "rt_degraded", {}, line);
  }
  return true;
}

void journal_port_event(const rt::CycleEvent& e) {
  const bool bad =
      e.kind == rt::CycleEventKind::PortLost || e.kind == rt::CycleEventKind::PortOpenFailed;
  log::event(bad ? log::Level::warn : log::Level::info, "rt",
             e.kind == rt::CycleEventKind::PortLost         ? "port_lost"
             : e.kind == rt::CycleEventKind::PortOpenFailed ? "port_open_failed"
             : e.kind == rt::CycleEventKind::PortOpened     ? "port_opened"
             : e.kind == rt::CycleEventKind::LineEcho       ? "line_echo"
                                                            : "thread_status",
             {}, rt::describe(e),
             bad ? std::optional(log::Catalogued::SerialPortLost) : std::nullopt);
}

io::EchoMode echo_mode(config::EchoMode mode) noexcept {
  switch (mode) {
    case config::EchoMode::on:
      return io::EchoMode::On;
    case config::EchoMode::off:
      return io::EchoMode::Off;
    case config::EchoMode::automatic:
      break;
  }
  return io::EchoMode::Auto;
}

nlohmann::json line_echo_json(io::EchoMode mode, io::EchoState state) {
  return {{"mode", std::string(io::to_string(mode))}, {"state", std::string(io::to_string(state))}};
}

api::ErrorCode to_api_error(lift::ReplyCode code) noexcept {
  switch (code) {
    case lift::ReplyCode::Ok:
      break;
    case lift::ReplyCode::NotReady:
      return api::ErrorCode::NotReady;
    case lift::ReplyCode::Busy:
      return api::ErrorCode::Busy;
    case lift::ReplyCode::BadRequest:
      return api::ErrorCode::BadRequest;
    case lift::ReplyCode::Fault:
      return api::ErrorCode::Fault;
    case lift::ReplyCode::Timeout:
      return api::ErrorCode::Timeout;
  }
  return api::ErrorCode::Internal;
}

}  // namespace liftd::daemon
