// The API server's watch/publish side: events queued for watchers, missed ones counted.
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "api/server_impl.hpp"

namespace liftd::api {

void Session::enqueue(std::shared_ptr<const std::string> line, bool is_event) {
  if (closed_) return;
  const ServerConfig& cfg = server_->config_;
  if (is_event) {
    const bool room = missed_ == 0 ? queue_.size() + 1 <= cfg.write_queue_max_messages &&
                                         queued_bytes_ + line->size() <= cfg.write_queue_max_bytes
                                   : drained();
    if (!room) {
      ++server_->counters_.missed_events;
      if (missed_++ == 0) {
        server_->log_(LogLevel::Warn, describe() + " does not read its events fast enough (" +
                                          std::to_string(queue_.size()) + " lines, " +
                                          std::to_string(queued_bytes_) +
                                          " bytes queued): events counted, not sent");
      }
      return;
    }
    if (missed_ != 0) {
      const std::uint64_t missed = std::exchange(missed_, 0);
      push_line(std::make_shared<const std::string>(event_line("missed", {{"count", missed}})));
    }
  }
  push_line(std::move(line));
}

void Session::set_watching(bool enable) {
  if (enable == watching_) return;
  watching_ = enable;
  if (enable) {
    ++server_->counters_.watchers;
  } else {
    --server_->counters_.watchers;
  }
}

void Session::send_event(std::string line) {
  enqueue(std::make_shared<const std::string>(std::move(line)), true);
}

void Server::Impl::publish(std::string_view event, const nlohmann::json& data) {
  ++counters_.events;
  if (counters_.watchers == 0) return;
  const auto line = std::make_shared<const std::string>(event_line(event, data));
  std::vector<std::shared_ptr<Session>> watchers;
  for (const auto& session : sessions_) {
    if (session->watching()) watchers.push_back(session);
  }
  for (const auto& session : watchers) session->enqueue(line, true);
}

}  // namespace liftd::api
