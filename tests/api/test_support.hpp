// A blocking test client and a fixture that runs the server on its own io thread.
#pragma once

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <asio.hpp>
#include <nlohmann/json.hpp>

#include "api/fake_backend.hpp"
#include "api/server.hpp"

namespace liftd::api::testing {

using namespace std::chrono_literals;

/// Blocking client over a Unix socket: one JSON line at a time, with timeouts.
class Client {
 public:
  explicit Client(const std::string& path) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  /// Takes a connected socket (e.g. one a child connected as another user).
  explicit Client(int connected_fd) : fd_(connected_fd) {}
  ~Client() {
    if (fd_ >= 0) ::close(fd_);
  }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  bool connected() const { return fd_ >= 0; }
  int fd() const { return fd_; }

  /// Writes all of `text`.
  bool send(std::string_view text) {
    while (!text.empty()) {
      const ssize_t n = ::send(fd_, text.data(), text.size(), MSG_NOSIGNAL);
      if (n <= 0) return false;
      text.remove_prefix(static_cast<std::size_t>(n));
    }
    return true;
  }
  /// Sends one JSON request line.
  bool send_json(const nlohmann::json& request) { return send(request.dump() + "\n"); }

  /// The next line without '\n'; nullopt on timeout, EOF or error (see `eof()`).
  std::optional<std::string> read_line(std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return std::nullopt;
      char chunk[65536];
      const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
      if (n <= 0) {
        eof_ = true;
        return std::nullopt;
      }
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }
  /// The next line parsed; nullopt on timeout/EOF.
  std::optional<nlohmann::json> read_json(std::chrono::milliseconds timeout = 5s) {
    auto line = read_line(timeout);
    if (!line) return std::nullopt;
    return nlohmann::json::parse(*line);
  }
  /// The next reply, skipping events.
  std::optional<nlohmann::json> read_reply(std::chrono::milliseconds timeout = 5s) {
    for (;;) {
      auto msg = read_json(timeout);
      if (!msg || !msg->contains("event")) return msg;
    }
  }
  /// Sends a request and returns its reply (events skipped).
  nlohmann::json call(const nlohmann::json& request) {
    if (!send_json(request)) return nullptr;
    auto reply = read_reply();
    return reply ? *reply : nlohmann::json(nullptr);
  }
  /// Reads the greeting.
  std::optional<nlohmann::json> read_hello() { return read_json(); }
  /// True once the server closed the connection (reads until EOF within `timeout`).
  bool wait_closed(std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!eof_ && std::chrono::steady_clock::now() < deadline) {
      read_line(std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now()));
    }
    return eof_;
  }
  bool eof() const { return eof_; }

 private:
  int fd_ = -1;
  std::string buffer_;
  bool eof_ = false;
};

/// A temp dir, a fake backend and a server on an io thread. `Fake`: FakeBackend, or a kind's fake
/// derived from it that serves the kind's own commands (tests/<kind>/api).
template <typename Fake>
class BasicServerFixture : public ::testing::Test {
 protected:
  BasicServerFixture() {
    char tmpl[] = "/tmp/liftd-api-test-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    std::filesystem::permissions(dir_, std::filesystem::perms::owner_all |
                                           std::filesystem::perms::group_exec |
                                           std::filesystem::perms::others_exec);
  }
  ~BasicServerFixture() override {
    stop_server();
    std::filesystem::remove_all(dir_);
  }

  std::string socket_path() const { return dir_ + "/api.sock"; }

  ServerConfig default_config() const {
    ServerConfig config;
    config.socket_path = socket_path();
    return config;
  }

  /// Starts the server (throws what Server::start throws) and the io thread.
  void start_server(ServerConfig config) {
    server_ = std::make_unique<Server>(io_, backend_, std::move(config),
                                       [](LogLevel, std::string_view) {});
    add_drive_kind_commands(server_->dispatcher(), backend_);
    server_->start();
    work_.emplace(io_.get_executor());
    thread_ = std::thread([this] { io_.run(); });
  }
  void start_server() { start_server(default_config()); }

  void stop_server() {
    if (thread_.joinable()) {
      on_io([this] { server_->stop(); });
      work_.reset();
      io_.stop();
      thread_.join();
    }
    server_.reset();
  }

  /// Runs `f` on the io thread and waits for it.
  template <typename F>
  auto on_io(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    asio::post(io_, [&task] { task(); });
    return result.get();
  }

  ServerCounters counters() {
    return on_io([this] { return server_->counters(); });
  }

  /// Waits until `pred()` (evaluated on the io thread) holds, up to `timeout`.
  template <typename P>
  bool eventually(P pred, std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (on_io(pred)) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }

  /// A connected client whose greeting has been read.
  std::unique_ptr<Client> connect() {
    auto client = std::make_unique<Client>(socket_path());
    if (client->connected()) client->read_hello();
    return client;
  }

  std::string dir_;
  asio::io_context io_;
  Fake backend_;
  std::unique_ptr<Server> server_;
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work_;
  std::thread thread_;
};

/// The server with the shared fake: the common commands served, every kind's known.
using ServerFixture = BasicServerFixture<FakeBackend>;

/// What a command printed (stdout and stderr) and its exit status (-1: it did not exit).
struct RunResult {
  int exit_code = -1;
  std::string output;
};

/// Runs `command_line` through the shell and collects its output.
inline RunResult run_command(const std::string& command_line) {
  RunResult r;
  std::FILE* pipe = ::popen((command_line + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.output.append(buf, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

#ifdef LIFTCTL_PATH
/// The in-process server with the liftctl binary pointed at its socket.
template <typename Fake>
class BasicLiftctlFixture : public BasicServerFixture<Fake> {
 protected:
  std::string liftctl(const std::string& args) const {
    return std::string(LIFTCTL_PATH) + " --socket " + this->socket_path() + " " + args;
  }
};
using LiftctlFixture = BasicLiftctlFixture<FakeBackend>;
#endif

}  // namespace liftd::api::testing
