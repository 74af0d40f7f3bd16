#include "daemon/lift_core.hpp"

#include "log/log.hpp"

namespace liftd::daemon {

std::uint32_t PendingReplies::add(api::Responder done, MonoTime deadline) {
  std::uint32_t tag = ++next_tag_;
  if (tag == 0) tag = next_tag_ = 1;
  pending_[tag] = Pending{std::move(done), deadline};
  return tag;
}

bool PendingReplies::complete(std::uint32_t tag, api::Result result) {
  auto it = pending_.find(tag);
  if (it == pending_.end()) return false;
  api::Responder done = std::move(it->second.done);
  pending_.erase(it);
  done(std::move(result));
  return true;
}

void PendingReplies::expire(MonoTime now, const std::string& message) {
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (now > it->second.deadline) {
      api::Responder done = std::move(it->second.done);
      it = pending_.erase(it);
      done(api::Result::fail(api::ErrorCode::Internal, message));
    } else {
      ++it;
    }
  }
}

void StatePublisher::publish(api::Server& server, api::StatusSnapshot status, MonoTime now) {
  if (last_ && status == *last_) return;
  // Position alone changes often while moving: rate-limited; anything else goes out at once.
  api::StatusSnapshot without_position = status;
  if (last_) without_position.position_mm = last_->position_mm;
  const bool discrete = !last_ || !(without_position == *last_);
  if (!discrete && now - last_publish_ < interval_) return;
  server.publish("state", api::to_json(status));
  last_ = std::move(status);
  last_publish_ = now;
}

void WindDown::start(std::function<void()> done, bool moving, MonoTime now) {
  done_ = std::move(done);
  until_ = now + deadline_;
  forced_ = false;
  if (moving) {
    log::event(log::Level::info, "travel", "shutdown_stopping_travel", {},
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
             std::string(active ? "fault: " : "fault cleared: ") + std::string(text));
  server.publish("fault", {{"code", name}, {"text", std::string(text)}, {"active", active}});
}

void report_call_served(api::Server& server, std::size_t floor) {
  log::event(log::Level::info, "travel", "call_served", {{"floor", std::to_string(floor)}},
             "call served: floor " + std::to_string(floor));
  server.publish("call_served", {{"floor", floor}});
}

}  // namespace liftd::daemon
