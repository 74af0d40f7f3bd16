// The API server's socket: bound here (a stale file cleared) or passed by systemd; start and stop.
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "api/server_impl.hpp"

namespace liftd::api {

namespace {

std::string errno_text(int error) {
  return std::strerror(error);
}

/// Throws unless `path` is free: removes a socket file nobody listens on.
void clear_stale_socket(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw std::runtime_error("api: cannot inspect " + path + ": " + errno_text(errno));
  }
  if (!S_ISSOCK(st.st_mode)) {
    throw std::runtime_error("api: " + path + " exists and is not a socket; not removing it");
  }
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("api: socket(): " + errno_text(errno));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  const int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  const int error = errno;
  ::close(fd);
  if (rc == 0) {
    throw std::runtime_error("api: another process is listening on " + path +
                             " (is liftd already running?)");
  }
  if (error != ECONNREFUSED) {
    throw std::runtime_error("api: cannot probe " + path + ": " + errno_text(error));
  }
  if (::unlink(path.c_str()) != 0) {
    throw std::runtime_error("api: cannot remove stale socket " + path + ": " + errno_text(errno));
  }
}

}  // namespace

void Server::Impl::start() {
  if (listening_) return;
  const std::string& path = config_.socket_path;
  asio::error_code ec;
  if (config_.listen_fd >= 0) {
    // Socket activation: systemd bound, set up and listens on it; its file stays systemd's.
    acceptor_.assign(asio::local::stream_protocol(), config_.listen_fd, ec);
    if (ec) {
      throw std::runtime_error("api: cannot use the socket systemd passed (fd " +
                               std::to_string(config_.listen_fd) + "): " + ec.message());
    }
    config_.listen_fd = -1;  // the acceptor owns it now
    listening_ = true;
    log_(LogLevel::Info, "api: listening on the socket systemd passed (" + path + ")");
    accept_next();
    return;
  }
  if (path.empty() || path.size() >= sizeof(sockaddr_un{}.sun_path)) {
    throw std::runtime_error("api: socket path \"" + path + "\" is empty or too long");
  }
  std::optional<gid_t> socket_gid;
  if (!config_.socket_group.empty()) socket_gid = resolve_group(config_.socket_group);
  clear_stale_socket(path);
  acceptor_.open(asio::local::stream_protocol(), ec);
  if (!ec) acceptor_.bind(asio::local::stream_protocol::endpoint(path), ec);
  if (ec) {
    acceptor_.close();
    throw std::runtime_error("api: cannot bind " + path + ": " + ec.message() +
                             " (does the directory exist?)");
  }
  created_socket_file_ = true;
  struct stat bound {};
  if (::lstat(path.c_str(), &bound) == 0) {
    socket_dev_ = bound.st_dev;
    socket_ino_ = bound.st_ino;
  }
  // Nobody can connect before listen(), so fixing the mode and group here leaves no window.
  if (::chmod(path.c_str(), static_cast<mode_t>(config_.socket_mode)) != 0) {
    const int error = errno;
    stop();
    throw std::runtime_error("api: chmod " + path + ": " + errno_text(error));
  }
  if (socket_gid && ::chown(path.c_str(), static_cast<uid_t>(-1), *socket_gid) != 0) {
    const int error = errno;
    stop();
    throw std::runtime_error("api: cannot give " + path + " to group " + config_.socket_group +
                             ": " + errno_text(error));
  }
  acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    stop();
    throw std::runtime_error("api: listen on " + path + ": " + ec.message());
  }
  listening_ = true;
  log_(LogLevel::Info, "api: listening on " + path);
  accept_next();
}

void Server::Impl::stop() {
  asio::error_code ignored;
  acceptor_.close(ignored);
  retry_timer_.cancel();
  budget_timer_.cancel();
  budget_queue_.clear();
  const auto sessions = std::vector<std::shared_ptr<Session>>(sessions_.begin(), sessions_.end());
  for (const auto& session : sessions) session->close("server stopping");
  sessions_.clear();
  if (created_socket_file_) {
    created_socket_file_ = false;
    const std::string& path = config_.socket_path;
    struct stat now {};
    if (::lstat(path.c_str(), &now) != 0) {
      log_(LogLevel::Info, "api: " + path + " is already gone");
    } else if (now.st_dev != socket_dev_ || now.st_ino != socket_ino_) {
      log_(LogLevel::Warn, "api: not removing " + path +
                               ": it is no longer the socket this daemon created (another "
                               "process has bound it since)");
    } else {
      ::unlink(path.c_str());
    }
  }
  if (config_.listen_fd >= 0) {  // passed by systemd but never taken over
    ::close(config_.listen_fd);
    config_.listen_fd = -1;
  }
  if (listening_) log_(LogLevel::Info, "api: stopped");
  listening_ = false;
}

}  // namespace liftd::api
