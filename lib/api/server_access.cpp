// The API server's access side: accepting a peer, its credentials, admission or refusal.
#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "api/server_impl.hpp"

namespace liftd::api {

void Server::Impl::accept_next() {
  acceptor_.async_accept([self = shared_from_this()](const asio::error_code& ec, Socket socket) {
    self->on_accept(ec, std::move(socket));
  });
}

void Server::Impl::on_accept(const asio::error_code& ec, Socket socket) {
  if (!listening_ || ec == asio::error::operation_aborted) return;
  if (ec) {
    log_(LogLevel::Warn, "api: accept failed: " + ec.message());
    retry_timer_.expires_after(kAcceptRetry);
    retry_timer_.async_wait([self = shared_from_this()](const asio::error_code& wait_ec) {
      if (!wait_ec && self->listening_) self->accept_next();
    });
    return;
  }
  accept_next();
  const auto creds = peer_credentials(socket.native_handle());
  if (!creds) {
    reject(std::move(socket), ErrorCode::Forbidden, "peer credentials unavailable");
    return;
  }
  Peer peer;
  peer.pid = creds->pid;
  peer.uid = creds->uid;
  peer.gid = creds->gid;
  peer.access = policy_.access_for(creds->uid, creds->groups);
  if (const auto refusal = admission_refusal(peer)) {
    reject(std::move(socket), ErrorCode::Busy, *refusal);
    return;
  }
  ++counters_.connections;
  ++counters_.clients;
  auto session = std::make_shared<Session>(shared_from_this(), std::move(socket), peer,
                                           creds->groups, next_session_id_++);
  sessions_.insert(session);
  log_(LogLevel::Debug, "api: client pid " + std::to_string(peer.pid) + " uid " +
                            std::to_string(peer.uid) + " connected");
  session->start();
}

std::optional<std::string> Server::Impl::admission_refusal(const Peer& peer) const {
  if (sessions_.size() >= config_.max_clients) {
    return "too many clients (limit " + std::to_string(config_.max_clients) + "); try later";
  }
  // The last reserved_clients slots are for control access, so that a read-only user holding
  // connections cannot lock the dispatcher or a technician out.
  const std::size_t open_slots = config_.max_clients > config_.reserved_clients
                                     ? config_.max_clients - config_.reserved_clients
                                     : 0;
  if (!peer.access.control && sessions_.size() >= open_slots) {
    return "too many clients: the last " + std::to_string(config_.reserved_clients) + " of " +
           std::to_string(config_.max_clients) +
           " connections are kept for control access; try later";
  }
  if (peer.uid != 0) {
    const auto same_uid = static_cast<std::size_t>(std::count_if(
        sessions_.begin(), sessions_.end(),
        [&](const std::shared_ptr<Session>& s) { return s->peer().uid == peer.uid; }));
    if (same_uid >= config_.max_clients_per_uid) {
      return "uid " + std::to_string(peer.uid) + " already has " + std::to_string(same_uid) +
             " connections (limit " + std::to_string(config_.max_clients_per_uid) +
             " per user); close one first";
    }
  }
  return std::nullopt;
}

void Server::Impl::reject(Socket socket, ErrorCode code, const std::string& message) {
  ++counters_.rejected;
  log_(LogLevel::Warn, "api: connection refused: " + message);
  auto held = std::make_shared<Socket>(std::move(socket));
  auto line = std::make_shared<const std::string>(reply_line(nullptr, Result::fail(code, message)));
  // The line fits an empty socket buffer, so this completes at once; then the socket closes.
  asio::async_write(*held, asio::buffer(*line), [held, line](const asio::error_code&, std::size_t) {
    asio::error_code ignored;
    held->shutdown(asio::socket_base::shutdown_both, ignored);
    held->close(ignored);
  });
}

}  // namespace liftd::api
