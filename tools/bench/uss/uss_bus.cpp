#include "bench/uss/uss_bus.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/mono_time.hpp"
#include "io/pty.hpp"
#include "uss/master/master.hpp"
#include "uss/runner/pty_line.hpp"
#include "uss/runner/uss_runner.hpp"
#include "uss/sim/uss_slave_sim.hpp"

namespace liftd::bench {

using namespace std::chrono_literals;

/// What UssBus runs: the simulated slaves behind the pty line thread, the master on its
/// runner's bus thread.
class UssBus::Parts {
  /// The user side of the USS bus: drains what the master reports, nothing else.
  class Hooks final : public uss::UssHooks {
   public:
    explicit Hooks(uss::Master& master) : master_(master) {}
    void after_exchange(MonoTime /*now*/) noexcept override {
      uss::LinkChange change;
      while (master_.poll_link_change(change)) {
      }
      uss::MirrorResult mirror;
      while (master_.poll_mirror(mirror)) {
      }
    }
    void on_port(bool /*up*/, MonoTime /*now*/) noexcept override {}

   private:
    uss::Master& master_;
  };

 public:
  Parts(int priority, bool lock_memory, int cpu)
      : pty_(make_pty()),
        slaves_(make_slaves()),
        bus_(std::make_unique<uss::sim::UssBusSim>(slaves_, kBaud, mono_now())),
        master_(std::make_unique<uss::Master>(master_config())),
        hooks_(*master_),
        line_(pty_.master_fd(), *bus_, kBaud) {
    uss::UssRunnerConfig rc;
    rc.device_path = pty_.slave_path();
    rc.serial = uss::uss_serial_settings(kBaud);
    rc.thread.priority = priority;
    rc.thread.lock_memory = lock_memory;
    rc.thread.cpu = cpu;
    runner_ = std::make_unique<uss::UssRunner>(rc, *master_, hooks_);
    line_priority_ = std::max(1, priority - 1);
    cpu_ = cpu;
  }
  ~Parts() { stop(); }
  int start() {
    if (const int err = line_.start(line_priority_, cpu_); err != 0) return err;
    return runner_->start();
  }
  void stop() {
    runner_->stop();
    line_.stop();
  }
  uss::UssRunnerStats stats() const { return runner_->stats(); }

 private:
  static io::PtyPair make_pty() {
    auto created = io::PtyPair::create(uss::uss_serial_settings(kBaud));
    if (!created.ok()) throw std::runtime_error(created.error().message());
    return std::move(created).value();
  }
  static std::vector<uss::sim::UssSlaveConfig> make_slaves() {
    std::vector<uss::sim::UssSlaveConfig> s(3);
    for (std::size_t i = 0; i < s.size(); ++i) {
      s[i].address = static_cast<std::uint8_t>(i + 1);
      s[i].reply_delay = 1ms;
    }
    return s;
  }
  uss::MasterConfig master_config() const {
    uss::MasterConfig mc;
    mc.baud = kBaud;
    mc.mirror_at_start = false;
    mc.expected_reply_delay = 1ms;
    for (const auto& s : slaves_) {
      mc.slaves.push_back(uss::SlaveConfig{s.address, uss::PkwLength::Four, 2});
      mc.polling_list.push_back(s.address);
    }
    return mc;
  }

  io::PtyPair pty_;
  std::vector<uss::sim::UssSlaveConfig> slaves_;
  std::unique_ptr<uss::sim::UssBusSim> bus_;
  std::unique_ptr<uss::Master> master_;
  Hooks hooks_;
  uss::testing::PtyLine<uss::sim::UssBusSim, uss::sim::UssReply> line_;
  std::unique_ptr<uss::UssRunner> runner_;
  int line_priority_ = 1;
  int cpu_ = -1;
};

UssBus::UssBus(int priority, bool lock_memory, int cpu)
    : parts_(std::make_unique<Parts>(priority, lock_memory, cpu)) {}

UssBus::~UssBus() = default;

int UssBus::start() {
  return parts_->start();
}

void UssBus::stop() {
  parts_->stop();
}

UssBusStats UssBus::stats() const {
  const uss::UssRunnerStats s = parts_->stats();
  UssBusStats out;
  out.counters.exchanges = s.counters.exchanges;
  out.counters.reply_timeouts = s.counters.reply_timeouts;
  out.counters.bad_replies = s.counters.bad_replies;
  out.wake_lateness = s.wake_lateness;
  return out;
}

}  // namespace liftd::bench
