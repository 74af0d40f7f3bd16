// The process-level test harness (harness.hpp), compiled once for every e2e binary.
#include "e2e/harness.hpp"

#include <gtest/gtest.h>

#include <iterator>

namespace liftd::e2e {

json Client::call(json request, std::chrono::milliseconds timeout) {
  request["id"] = ++id_;
  if (!api_.send(request)) return nullptr;
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    const json reply = next(end);
    if (reply.is_object() && reply.contains("id") && reply["id"] == id_) return reply;
  }
  return nullptr;
}

json Client::wait_event(const std::string& name, const std::function<bool(const json&)>& match,
                        std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (true) {
    for (; cursor_ < events_.size(); ++cursor_) {
      const json& e = events_[cursor_];
      if (e["event"] == name && match(e["data"])) return events_[cursor_++];
    }
    if (Clock::now() >= end) return nullptr;
    next(std::min(end, Clock::now() + 200ms));
  }
}

void Client::drain(std::chrono::milliseconds duration) {
  const auto end = Clock::now() + duration;
  while (Clock::now() < end) next(end);
}

json Client::next(Clock::time_point end) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
  if (left.count() <= 0) return nullptr;
  json line = api_.next(left);
  if (line.is_object() && line.contains("event")) events_.push_back(line);
  return line;
}

std::vector<std::string> daemon_env() {
  std::vector<std::string> env = {"PATH=/usr/bin:/bin", "TZ=UTC"};
  for (const char* name : {"ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS"}) {
    if (const char* value = std::getenv(name)) env.push_back(std::string(name) + "=" + value);
  }
  return env;
}

Lift::Lift(const std::string& name, int dcp, const json& travel,
           const std::vector<std::string>& wrapper, const json& extra) {
  std::string leaf = name;  // a parameterised test's name has a '/'
  std::replace(leaf.begin(), leaf.end(), '/', '-');
  dir_ = std::filesystem::temp_directory_path() /
         ("liftd-e2e-" + std::to_string(::getpid()) + "-" + leaf);
  std::filesystem::remove_all(dir_);
  std::filesystem::create_directories(dir_);
  socket_ = (dir_ / "api.sock").string();
  json config = {{"log", {{"level", "info"}}},
                 {"api",
                  {{"socket", socket_},
                   {"socket_group", ""},
                   {"read_group", ""},
                   {"control_group", ""},
                   {"inputs_group", ""}}},
                 {"sim", {{"dcp", dcp}}}};
  if (!travel.empty()) config["travel"] = travel;
  config.merge_patch(extra);
  const std::string config_path = (dir_ / "liftd.json").string();
  std::ofstream(config_path) << config.dump(2);
  std::vector<std::string> args = wrapper;
  for (const char* arg : {LIFTD_BINARY, "--simulate", "--config"}) args.emplace_back(arg);
  args.push_back(config_path);
  daemon_ = std::make_unique<liftd::testing::Process>(args, daemon_env(), dir_.string(), "liftd");
  // The link is up once I0, I1 and I3 went through (well under a second on a quiet machine;
  // 30 s allows for a loaded one).
  for (int i = 0; i < 300; ++i) {
    auto client = std::make_unique<Client>(socket_);
    if (client->connected()) {
      const json status = client->call({{"cmd", "status"}});
      if (status.is_object() && status["result"]["link"]["state"] == "up" &&
          status["result"]["car"]["floor"] == 0) {
        client_ = std::move(client);
        const json watch = client_->call({{"cmd", "watch"}, {"enable", true}});
        if (!watch.is_object() || !watch.value("ok", false)) error_ = "watch refused";
        return;
      }
    }
    std::this_thread::sleep_for(100ms);
  }
  error_ = "the link did not come up: " + daemon_->err();
}

Lift::~Lift() {
  client_.reset();
  if (daemon_) {
    daemon_->signal(SIGTERM);
    daemon_->wait(5s);
    daemon_.reset();
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

std::optional<int> Lift::stop_daemon(int signal_number, std::chrono::milliseconds timeout) {
  daemon_->signal(signal_number);
  return daemon_->wait(timeout);
}

json Lift::status() {
  return client_->call({{"cmd", "status"}})["result"];
}

bool Lift::wait_drive_state(const std::string& state, std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    if (status()["drive"]["state"] == state) return true;
    client_->drain(50ms);
  }
  return false;
}

std::vector<std::filesystem::path> Lift::trace_files() const {
  std::vector<std::filesystem::path> out;
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("liftd-trace-", 0) == 0 && entry.path().extension() == ".txt") {
      out.push_back(entry.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double Lift::position_mm() {
  const json p = status()["car"]["position_mm"];
  return p.is_number() ? p.get<double>() : std::nan("");
}

json Lift::wait_travel_end(std::chrono::milliseconds timeout) {
  return client_->wait_event(
      "travel", [](const json& d) { return d["event"] == "finished" || d["event"] == "aborted"; },
      timeout);
}

json Lift::wait_travel(const std::string& type, std::chrono::milliseconds timeout) {
  return client_->wait_event(
      "travel", [&](const json& d) { return d["event"] == type; }, timeout);
}

bool Lift::wait_moved(double from_mm, double mm, std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    const double p = position_mm();
    if (std::abs(p - from_mm) >= mm) return true;
    client_->drain(30ms);
  }
  return false;
}

std::vector<std::pair<std::int64_t, int>> Lift::newest_commands(int count) {
  std::vector<std::pair<std::int64_t, int>> out;
  const json trace = client_->call({{"cmd", "trace"}, {"count", count}});
  for (const auto& f : trace["result"]["frames"]) {
    const std::string tx = f["tx"];
    out.emplace_back(f["t_us"].get<std::int64_t>(), std::stoi(tx.substr(0, 2), nullptr, 16));
  }
  return out;
}

bool Lift::b0_off_in_newest(int count) {
  const auto end = Clock::now() + 2s;
  while (true) {
    const auto frames = newest_commands(count);
    const bool off = !frames.empty() && std::all_of(frames.begin(), frames.end(),
                                                    [](auto& f) { return (f.second & 0x01) == 0; });
    if (off || Clock::now() >= end) return off;
    client_->drain(50ms);
  }
}

int Lift::count_events(const std::string& name, const std::function<bool(const json&)>& match) {
  return static_cast<int>(
      std::count_if(client_->events().begin(), client_->events().end(),
                    [&](const json& e) { return e["event"] == name && match(e["data"]); }));
}

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string expect_trace_save_writes_file(Lift& lift, const std::string& kind, int min_records) {
  const json r = lift.call({{"cmd", "trace"}, {"count", 1}, {"save", true}});
  EXPECT_TRUE(r.value("ok", false)) << r.dump();
  if (!r.value("ok", false)) return "";
  EXPECT_EQ(r["result"]["frames"].size(), 1U) << r.dump();
  const std::string path = r["result"]["file"];
  EXPECT_EQ(std::filesystem::path(path).parent_path(), lift.dir());
  EXPECT_EQ(std::filesystem::path(path).filename().string().rfind("liftd-trace-", 0), 0U) << path;
  EXPECT_GT(r["result"]["records"].get<int>(), min_records) << r.dump();
  EXPECT_NE(lift.log().find(kind + ": flight recorder ("), std::string::npos) << lift.log();
  EXPECT_NE(lift.log().find("after request [event=trace_written path=" + path), std::string::npos)
      << lift.log();
  const json again = lift.call({{"cmd", "trace"}, {"save", true}});
  EXPECT_EQ(again["error"]["code"], "busy") << again.dump();
  return file_text(path);
}

std::string expect_sigusr1_writes_file(Lift& lift) {
  EXPECT_TRUE(lift.trace_files().empty());
  lift.signal(SIGUSR1);
  for (int i = 0; i < 100 && lift.log().find("after SIGUSR1") == std::string::npos; ++i) {
    lift.api().drain(50ms);
  }
  const std::vector<std::filesystem::path> files = lift.trace_files();
  EXPECT_EQ(files.size(), 1U) << lift.log();
  if (files.size() != 1) return "";
  EXPECT_NE(lift.log().find("written to " + files.front().string() + " after SIGUSR1"),
            std::string::npos)
      << lift.log();
  EXPECT_EQ(lift.status()["link"]["state"], "up") << "the daemon runs on";
  return file_text(files.front());
}

std::int64_t mono_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
      .count();
}

}  // namespace liftd::e2e
