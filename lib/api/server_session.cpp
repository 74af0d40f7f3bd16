// The API server's connection and line handling: a client's reads, turns, budget, writes, timeouts.
#include <poll.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "api/server_impl.hpp"

namespace liftd::api {

void Session::close(std::string_view reason) {
  if (closed_) return;
  closed_ = true;
  if (watching_) --server_->counters_.watchers;
  watching_ = false;
  --server_->counters_.clients;
  server_->log_(LogLevel::Debug, describe() + " closed: " + std::string(reason));
  asio::error_code ignored;
  timer_.cancel();
  socket_.shutdown(asio::socket_base::shutdown_both, ignored);
  socket_.close(ignored);
  queue_.clear();
  queued_bytes_ = 0;
  server_->remove(shared_from_this());
}

void Session::push_line(std::shared_ptr<const std::string> line) {
  queued_bytes_ += line->size();
  queue_.push_back(std::move(line));
  if (!writing_) write_next();
}

std::string Session::describe() const {
  return "api client #" + std::to_string(id_) + " (pid " + std::to_string(peer_.pid) + ", uid " +
         std::to_string(peer_.uid) + ")";
}

bool Session::backlogged() const {
  const ServerConfig& cfg = server_->config_;
  return queue_.size() + in_flight_ >= cfg.write_queue_max_messages ||
         queued_bytes_ >= cfg.write_queue_max_bytes;
}

bool Session::drained() const {
  const ServerConfig& cfg = server_->config_;
  return queue_.size() + in_flight_ <= cfg.write_queue_max_messages / 2 &&
         queued_bytes_ <= cfg.write_queue_max_bytes / 2;
}

void Session::read_more() {
  if (reading_ || closed_ || closing_ || peer_done_) return;
  reading_ = true;
  socket_.async_read_some(asio::buffer(chunk_),
                          [self = shared_from_this()](const asio::error_code& ec, std::size_t n) {
                            self->reading_ = false;
                            self->on_read(ec, n);
                          });
}

void Session::on_read(const asio::error_code& ec, std::size_t n) {
  if (closed_) return;
  if (ec == asio::error::eof) {
    // A client that closed its socket is gone (POLLHUP: both directions shut down): nothing
    // can reach it. One that only shut down writing (half-close) has said all it will:
    // answer what it sent (a last line without a newline counts), then close once every
    // reply is written.
    pollfd probe{socket_.native_handle(), POLLOUT, 0};
    if (::poll(&probe, 1, 0) > 0 && (probe.revents & (POLLHUP | POLLERR)) != 0) {
      close("client disconnected");
      return;
    }
    peer_done_ = true;
    if (!closing_ && !pending_.empty()) {
      pending_ += '\n';
      process_lines();
      if (closed_) return;
    }
    if (!turn_owed_) pending_.clear();  // else its next turn handles the rest
    close_if_done();
    if (!closed_) arm_timer();
    return;
  }
  if (ec) {
    close("read failed: " + ec.message());
    return;
  }
  if (closing_) return;
  if (pending_.empty() && n > 0) partial_since_ = SteadyClock::now();
  pending_.append(chunk_.data(), n);
  process_lines();
  if (closed_) return;
  if (!closing_ && !paused_ && !turn_owed_) read_more();
  arm_timer();
}

void Session::process_lines() {
  const std::size_t max_line = server_->config_.max_line_bytes;
  std::size_t start = 0;
  std::size_t lines = 0;
  paused_ = false;
  while (!closed_ && !closing_) {
    if (backlogged()) {
      // Backpressure: leave the rest unread until the client has taken its replies.
      paused_ = true;
      break;
    }
    const std::size_t newline = pending_.find('\n', start);
    if (newline == std::string::npos) break;
    if (lines++ == kLinesPerTurn) {
      // Fair share: the rest waits for this client's next turn; reading waits with it.
      owe_turn();
      break;
    }
    if (!server_->take_budget()) {
      // The requests of all clients together reached api.max_requests_per_s.
      wait_for_budget();
      break;
    }
    std::string_view line(pending_.data() + start, newline - start);
    start = newline + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.size() > max_line) {
      fail_and_close(ErrorCode::TooLarge, too_large_message());
      break;
    }
    last_request_ = SteadyClock::now();
    if (line.find_first_not_of(" \t") == std::string_view::npos) continue;
    handle(line);
  }
  if (closed_) return;
  pending_.erase(0, start);
  if (!closing_ && !paused_ && !turn_owed_ && pending_.size() > max_line) {
    fail_and_close(ErrorCode::TooLarge, too_large_message());
  }
  if (closed_) return;
  if (start > 0 && !pending_.empty()) partial_since_ = SteadyClock::now();
}

void Session::owe_turn() {
  if (turn_owed_) return;
  turn_owed_ = true;
  asio::post(server_->io_, [self = shared_from_this()] { self->take_turn(); });
}

void Session::wait_for_budget() {
  if (turn_owed_) return;
  turn_owed_ = true;
  ++server_->counters_.budget_waits;
  server_->wait_for_budget(shared_from_this());
}

void Session::take_turn() {
  turn_owed_ = false;
  if (closed_) return;
  handle_waiting_lines();
}

void Session::maybe_resume() {
  if (!paused_ || closed_ || closing_ || !drained()) return;
  handle_waiting_lines();
}

void Session::handle_waiting_lines() {
  process_lines();
  if (closed_) return;
  if (peer_done_) {
    close_if_done();
  } else if (!paused_ && !turn_owed_ && !closing_) {
    read_more();
  }
  if (!closed_) arm_timer();
}

void Session::close_if_done() {
  if (closed_ || !peer_done_ || paused_ || turn_owed_) return;
  if (in_flight_ == 0 && queue_.empty() && !writing_) close("client finished (half-close)");
}

std::string Session::too_large_message() const {
  return "request line longer than " + std::to_string(server_->config_.max_line_bytes) +
         " bytes; closing";
}

void Session::handle(std::string_view line) {
  ++server_->counters_.requests;
  ++in_flight_;
  // Holds the session weakly: a backend may answer after the client (or the server) is gone.
  std::weak_ptr<Session> weak = shared_from_this();
  server_->dispatcher_.handle_line(line, peer_, *this, [weak](std::string reply, bool ok) {
    const auto self = weak.lock();
    if (!self || self->closed_) return;
    if (!ok) ++self->server_->counters_.errors;
    --self->in_flight_;
    self->enqueue(std::make_shared<const std::string>(std::move(reply)), false);
    if (!self->closed_) self->arm_timer();
  });
}

void Session::fail_and_close(ErrorCode code, const std::string& message) {
  ++server_->counters_.errors;
  enqueue(std::make_shared<const std::string>(reply_line(nullptr, Result::fail(code, message))),
          false);
  if (closed_) return;
  closing_ = true;
  close_deadline_ = SteadyClock::now() + kFlushGrace;
  server_->log_(LogLevel::Info, describe() + ": " + message);
  arm_timer();
}

void Session::write_next() {
  if (queue_.empty() || closed_) {
    writing_ = false;
    if (closing_ && !closed_) close("closed after error");
    if (!closed_) close_if_done();
    return;
  }
  if (!writing_) write_since_ = SteadyClock::now();
  writing_ = true;
  const auto line = queue_.front();
  asio::async_write(socket_, asio::buffer(*line),
                    [self = shared_from_this(), line](const asio::error_code& ec, std::size_t) {
                      if (self->closed_) return;
                      if (ec) {
                        self->close("write failed: " + ec.message());
                        return;
                      }
                      self->queued_bytes_ -= line->size();
                      self->queue_.pop_front();
                      self->write_since_ = SteadyClock::now();  // the client took a line
                      self->write_next();
                      self->maybe_resume();
                      if (!self->closed_) self->arm_timer();
                    });
}

std::optional<SteadyClock::time_point> Session::deadline() const {
  const ServerConfig& cfg = server_->config_;
  if (closing_) return close_deadline_;
  if (writing_) return write_since_ + cfg.stalled_reader_timeout;
  if (peer_done_ || paused_ || turn_owed_) return std::nullopt;
  if (!pending_.empty()) return partial_since_ + cfg.partial_line_timeout;
  if (cfg.idle_timeout.count() > 0 && !watching_ && in_flight_ == 0) {
    return last_request_ + cfg.idle_timeout;
  }
  return std::nullopt;
}

void Session::arm_timer() {
  const auto due = deadline();
  if (!due || (armed_ && *armed_ <= *due)) return;
  armed_ = due;
  timer_.expires_at(*due);
  timer_.async_wait([self = shared_from_this()](const asio::error_code& ec) {
    if (!ec) self->on_timer();
  });
}

void Session::on_timer() {
  if (closed_) return;
  armed_.reset();
  const auto now = SteadyClock::now();
  const auto due = deadline();
  if (!due || now < *due) {
    arm_timer();
    return;
  }
  if (closing_) {
    close("client did not take its last error line");
    return;
  }
  const ServerConfig& cfg = server_->config_;
  if (writing_) {
    // It cannot take a message either: log it and close.
    ++server_->counters_.dropped;
    server_->log_(LogLevel::Warn, describe() + " dropped: it took none of its " +
                                      std::to_string(queue_.size()) + " queued lines for " +
                                      std::to_string(cfg.stalled_reader_timeout.count()) + " ms");
    close("stalled reader");
    return;
  }
  ++server_->counters_.timeouts;
  if (!pending_.empty()) {
    fail_and_close(ErrorCode::Timeout, "request line not finished with a newline within " +
                                           std::to_string(cfg.partial_line_timeout.count()) +
                                           " ms; closing");
  } else {
    fail_and_close(ErrorCode::Timeout, "no request for " +
                                           std::to_string(cfg.idle_timeout.count()) +
                                           " ms; closing idle connection");
  }
}

void Server::Impl::wait_for_budget(std::shared_ptr<Session> session) {
  budget_queue_.push_back(std::move(session));
  arm_budget_timer();
}

void Server::Impl::arm_budget_timer() {
  if (budget_timer_armed_ || budget_queue_.empty()) return;
  budget_timer_armed_ = true;
  budget_timer_.expires_at(budget_.next_at(SteadyClock::now()));
  budget_timer_.async_wait([weak = weak_from_this()](const asio::error_code& ec) {
    const auto self = weak.lock();
    if (!self || ec) return;
    self->budget_timer_armed_ = false;
    self->on_budget_timer();
  });
}

void Server::Impl::on_budget_timer() {
  // Each client that waited takes its turn in order while there is budget; one that runs out
  // again goes to the back. At most one round per expiry: the next comes with the budget.
  for (std::size_t n = budget_queue_.size(); n > 0 && !budget_queue_.empty(); --n) {
    const auto now = SteadyClock::now();
    if (budget_.next_at(now) > now) break;
    const auto session = std::move(budget_queue_.front());
    budget_queue_.pop_front();
    session->take_turn();
  }
  arm_budget_timer();
}

}  // namespace liftd::api
