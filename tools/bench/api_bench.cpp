// api-bench: requests per second and latency of `status` with 1, 8 and 32 clients.
//   api-bench                   in-process server with a fake backend in a temp dir
//   api-bench --socket PATH     against a running liftd
//   api-bench --serve PATH      only serve the fake backend at PATH (for trying liftctl)
//   --seconds N                 measuring time per client count (default 2)
//   --baseline PATH             instead: a bare single-threaded epoll line server (no JSON, no
//                               Asio) answering every line with a fixed reply the size of a
//                               status reply: the ceiling of one io thread on this machine
//   --pipeline N                instead: one client writes N requests without waiting and reads
//                               every reply (backpressure, not disconnection); exit 1 if any is
//                               missing or out of order
#include <poll.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <asio.hpp>

#include "api/fake_backend.hpp"
#include "api/server.hpp"

namespace {

using Clock = std::chrono::steady_clock;

/// Length of the baseline server's reply line: that of a status reply from liftd --simulate.
constexpr std::size_t kBaselineReplyBytes = 800;

int connect_to(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

/// Reads until `lines` newlines arrived; false on EOF/error.
bool read_lines(int fd, int lines, std::string& buffer) {
  while (lines > 0) {
    const auto nl = buffer.find('\n');
    if (nl != std::string::npos) {
      buffer.erase(0, nl + 1);
      --lines;
      continue;
    }
    char chunk[16384];
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) return false;
    buffer.append(chunk, static_cast<std::size_t>(n));
  }
  return true;
}

struct ClientResult {
  std::vector<double> latencies_us;
  bool failed = false;
};

/// One client: request, wait for the reply, repeat until `until`.
void run_client(const std::string& path, Clock::time_point start, Clock::time_point until,
                ClientResult& result) {
  const int fd = connect_to(path);
  if (fd < 0) {
    result.failed = true;
    return;
  }
  std::string buffer;
  if (!read_lines(fd, 1, buffer)) result.failed = true;  // greeting
  std::this_thread::sleep_until(start);
  static const std::string request = "{\"cmd\":\"status\",\"id\":1}\n";
  while (!result.failed && Clock::now() < until) {
    const auto t0 = Clock::now();
    if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) !=
            static_cast<ssize_t>(request.size()) ||
        !read_lines(fd, 1, buffer)) {
      result.failed = true;
      break;
    }
    result.latencies_us.push_back(
        std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  ::close(fd);
}

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

bool bench(const std::string& path, int clients, double seconds) {
  std::vector<ClientResult> results(static_cast<std::size_t>(clients));
  std::vector<std::thread> threads;
  const auto start = Clock::now() + std::chrono::milliseconds(200);
  const auto until =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  for (auto& r : results) {
    threads.emplace_back([&path, start, until, &r] { run_client(path, start, until, r); });
  }
  for (auto& t : threads) t.join();
  std::vector<double> all;
  for (const auto& r : results) {
    if (r.failed) {
      std::fprintf(stderr, "api-bench: a client failed (max_clients too low?)\n");
      return false;
    }
    all.insert(all.end(), r.latencies_us.begin(), r.latencies_us.end());
  }
  const double rate = static_cast<double>(all.size()) / seconds;
  const double p50 = percentile(all, 0.50);
  const double p99 = percentile(all, 0.99);
  std::printf("%7d %12.0f %10.1f %10.1f %10zu\n", clients, rate, p50, p99, all.size());
  return true;
}

/// One client writes `count` requests without waiting (a writer thread) while reading the
/// replies; every id must come back, in order.
bool pipeline(const std::string& path, long count) {
  const int fd = connect_to(path);
  if (fd < 0) {
    std::fprintf(stderr, "api-bench: cannot connect to %s\n", path.c_str());
    return false;
  }
  std::string buffer;
  if (!read_lines(fd, 1, buffer)) {
    std::fprintf(stderr, "api-bench: no greeting\n");
    ::close(fd);
    return false;
  }
  const auto t0 = Clock::now();
  bool sent_all = true;
  std::thread writer([fd, count, &sent_all] {
    std::string batch;
    for (long i = 0; i < count; ++i) {
      batch += "{\"cmd\":\"status\",\"id\":" + std::to_string(i) + "}\n";
      if (batch.size() >= 64 * 1024 || i + 1 == count) {
        std::string_view rest(batch);
        while (!rest.empty()) {
          const ssize_t n = ::send(fd, rest.data(), rest.size(), MSG_NOSIGNAL);
          if (n <= 0) {
            sent_all = false;
            return;
          }
          rest.remove_prefix(static_cast<std::size_t>(n));
        }
        batch.clear();
      }
    }
  });
  long received = 0;
  bool in_order = true;
  while (received < count) {
    const auto nl = buffer.find('\n');
    if (nl == std::string::npos) {
      char chunk[65536];
      const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
      if (n <= 0) break;
      buffer.append(chunk, static_cast<std::size_t>(n));
      continue;
    }
    const std::string expected = "{\"id\":" + std::to_string(received) + ",";
    if (buffer.compare(0, expected.size(), expected) != 0) in_order = false;
    buffer.erase(0, nl + 1);
    ++received;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  ::shutdown(fd, SHUT_RDWR);
  writer.join();
  ::close(fd);
  std::printf("api-bench: pipelined %ld status requests on %s\n", count, path.c_str());
  std::printf("%10s %10s %12s %10s\n", "sent", "replies", "requests/s", "seconds");
  std::printf("%10ld %10ld %12.0f %10.3f\n", sent_all ? count : -1L, received,
              static_cast<double>(received) / seconds, seconds);
  if (received != count || !in_order) {
    std::fprintf(stderr, "api-bench: %ld of %ld replies%s\n", received, count,
                 in_order ? "" : ", not in order");
    return false;
  }
  return true;
}

/// The reference for the API figures: the least a single-threaded line server must do per
/// request on this machine (epoll_wait, recv, send), with nothing of liftd in it. Replies are
/// `reply_bytes` long so the copy costs the same as a real status reply.
class BaselineServer {
 public:
  BaselineServer(const std::string& path, std::size_t reply_bytes) {
    reply_ = "{\"id\":1,\"ok\":true,\"result\":\"";
    reply_.append(reply_bytes > reply_.size() + 3 ? reply_bytes - reply_.size() - 3 : 0, 'x');
    reply_ += "\"}\n";
    listener_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    ::unlink(path.c_str());
    if (::bind(listener_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
        ::listen(listener_, 64) != 0) {
      std::perror("api-bench: baseline server");
      std::exit(1);
    }
    epoll_ = ::epoll_create1(EPOLL_CLOEXEC);
    add(listener_);
    thread_ = std::thread([this] { run(); });
  }
  ~BaselineServer() {
    stop_.store(true);
    thread_.join();
    for (auto& [fd, pending] : clients_) ::close(fd);
    ::close(epoll_);
    ::close(listener_);
  }

 private:
  void add(int fd) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = fd;
    ::epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &ev);
  }
  void run() {
    std::array<epoll_event, 64> events{};
    char chunk[16384];
    while (!stop_.load()) {
      const int n = ::epoll_wait(epoll_, events.data(), static_cast<int>(events.size()), 100);
      for (int i = 0; i < n; ++i) {
        const int fd = events[static_cast<std::size_t>(i)].data.fd;
        if (fd == listener_) {
          const int client = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
          if (client < 0) continue;
          add(client);
          clients_[client];
          [[maybe_unused]] const ssize_t w = ::send(client, "{}\n", 3, MSG_NOSIGNAL);  // greeting
          continue;
        }
        const ssize_t got = ::recv(fd, chunk, sizeof chunk, 0);
        if (got <= 0) {
          ::epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
          ::close(fd);
          clients_.erase(fd);
          continue;
        }
        const auto lines = std::count(chunk, chunk + got, '\n');
        for (long k = 0; k < lines; ++k) {
          [[maybe_unused]] const ssize_t w = ::send(fd, reply_.data(), reply_.size(), MSG_NOSIGNAL);
        }
      }
    }
  }

  std::string reply_;
  int listener_ = -1;
  int epoll_ = -1;
  std::map<int, int> clients_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  std::string external;
  std::string serve_path;
  double seconds = 2.0;
  long pipeline_count = 0;
  std::string baseline_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--socket" && i + 1 < argc) {
      external = argv[++i];
    } else if (arg == "--serve" && i + 1 < argc) {
      serve_path = argv[++i];
    } else if (arg == "--seconds" && i + 1 < argc) {
      seconds = std::atof(argv[++i]);
    } else if (arg == "--baseline" && i + 1 < argc) {
      baseline_path = argv[++i];
    } else if (arg == "--pipeline" && i + 1 < argc) {
      pipeline_count = std::atol(argv[++i]);
      if (pipeline_count <= 0) {
        std::fprintf(stderr, "api-bench: --pipeline needs a positive count\n");
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: api-bench [--socket PATH | --serve PATH | --baseline PATH] "
                   "[--seconds N] [--pipeline N]\n");
      return 2;
    }
  }

  if (!baseline_path.empty()) {
    // As long as a status reply of liftd --simulate at rest (797 bytes measured).
    const BaselineServer baseline(baseline_path, kBaselineReplyBytes);
    std::printf("api-bench: bare epoll line server (baseline) on %s, %.1f s per client count\n",
                baseline_path.c_str(), seconds);
    std::printf("%7s %12s %10s %10s %10s\n", "clients", "requests/s", "p50 us", "p99 us",
                "requests");
    bool ok = true;
    for (const int clients : {1, 8, 32}) ok = bench(baseline_path, clients, seconds) && ok;
    ::unlink(baseline_path.c_str());
    return ok ? 0 : 1;
  }

  asio::io_context io;
  liftd::api::testing::FakeBackend backend;
  std::unique_ptr<liftd::api::Server> server;
  std::string dir;
  std::string path = external;
  if (external.empty()) {
    liftd::api::ServerConfig config;
    if (serve_path.empty()) {
      char tmpl[] = "/tmp/liftd-api-bench-XXXXXX";
      dir = ::mkdtemp(tmpl);
      config.socket_path = dir + "/api.sock";
    } else {
      config.socket_path = serve_path;
    }
    config.max_clients = 64;
    path = config.socket_path;
    server = std::make_unique<liftd::api::Server>(io, backend, config,
                                                  [](liftd::api::LogLevel, std::string_view) {});
    server->start();
  }
  if (!serve_path.empty()) {
    // Serve until SIGINT/SIGTERM, publishing the state once a second so watchers see traffic.
    asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const asio::error_code&, int) {
      server->stop();
      io.stop();
    });
    asio::steady_timer tick(io);
    std::function<void()> arm = [&] {
      tick.expires_after(std::chrono::seconds(1));
      tick.async_wait([&](const asio::error_code& ec) {
        if (ec) return;
        backend.status_snapshot.position_mm = *backend.status_snapshot.position_mm + 10;
        server->publish("state", liftd::api::to_json(backend.status_snapshot));
        arm();
      });
    };
    arm();
    std::printf("api-bench: serving a fake backend on %s (Ctrl-C to stop)\n", path.c_str());
    std::fflush(stdout);
    io.run();
    return 0;
  }

  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work;
  std::thread io_thread;
  if (server) {
    work.emplace(io.get_executor());
    io_thread = std::thread([&io] { io.run(); });
  }
  bool ok = true;
  if (pipeline_count > 0) {
    ok = pipeline(path, pipeline_count);
  } else {
    std::printf("api-bench: status round trips on %s, %.1f s per client count\n", path.c_str(),
                seconds);
    std::printf("%7s %12s %10s %10s %10s\n", "clients", "requests/s", "p50 us", "p99 us",
                "requests");
    for (const int clients : {1, 8, 32}) ok = bench(path, clients, seconds) && ok;
  }
  if (server) {
    asio::post(io, [&] { server->stop(); });
    work.reset();
    io_thread.join();
    server.reset();
    std::filesystem::remove_all(dir);
  }
  return ok ? 0 : 1;
}
