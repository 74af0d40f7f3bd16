// tools/dcp-drive-sim against a small master loop over a real pty pair: frames answered in
// time, the channel works end to end, and a torn frame is resynchronised by the gap.
// Real time on shared cores: asserts on counts with generous margins.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <string>
#include <thread>
#include <vector>

#include "common/mono_time.hpp"
#include "dcp/frame.hpp"
#include "io/pty.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;

class DriveSimProcess {
 public:
  explicit DriveSimProcess(const std::string& device) {
    std::vector<std::string> args = {DCP_DRIVE_SIM_PATH, "--device", device, "--quiet"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ok_ = posix_spawn(&pid_, DCP_DRIVE_SIM_PATH, nullptr, nullptr, argv.data(), environ) == 0;
  }
  ~DriveSimProcess() {
    if (!ok_) return;
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  bool ok() const { return ok_; }

 private:
  pid_t pid_ = -1;
  bool ok_ = false;
};

struct Master {
  liftd::io::SerialPort port;
  std::vector<std::uint8_t> channel_rx;

  // Sends one frame and waits up to `wait` for a 6-byte reply; true if it decodes. The tool
  // answers within a millisecond or two; a loaded machine may take longer, and the test counts
  // what the tool answered, so the master waits until the reply is certainly not coming.
  bool exchange(const liftd::dcp::MasterFrame& f, std::chrono::milliseconds wait = 400ms) {
    const auto bytes = liftd::dcp::encode(f);
    if (port.write_frame(bytes).status != liftd::io::IoStatus::Ok) return false;
    std::array<std::uint8_t, 6> reply{};
    const auto r = port.read_until(reply, liftd::mono_now() + wait);
    if (r.status != liftd::io::IoStatus::Ok) {
      (void)port.flush_input();
      return false;
    }
    const auto s = liftd::dcp::decode_slave(reply);
    if (!s) return false;
    if (s->comm1 != 0) channel_rx.push_back(s->comm1);
    if (s->comm2 != 0) channel_rx.push_back(s->comm2);
    return true;
  }
};

// Waits until the tool answers (it has started, opened the port and flushed it), however long
// a loaded machine takes to start a process: idle frames until one reply decodes, then a flush.
bool wait_answering(Master& m) {
  const MonoTime until = liftd::mono_now() + 20s;
  while (liftd::mono_now() < until) {
    if (m.exchange(liftd::dcp::MasterFrame{}, 100ms)) {
      std::this_thread::sleep_for(20ms);
      (void)m.port.flush_input();
      return true;
    }
  }
  return false;
}

TEST(DcpDriveSimTool, AnswersFramesOverPtyAndCarriesTheChannel) {
  auto pair = liftd::io::PtyPair::create();
  ASSERT_TRUE(pair.ok()) << pair.error().message();
  const std::string slave = pair.value().slave_path();
  Master m{pair.value().take_master(), {}};
  DriveSimProcess sim(slave);
  ASSERT_TRUE(sim.ok());
  ASSERT_TRUE(wait_answering(m)) << "the tool never answered";

  // An I0 message in the channel bytes, then idle.
  const std::string i0 = std::string("\x02\x1CI0LI0100010126DE\x03");
  std::size_t tx = 0;
  int good = 0;
  constexpr int kFrames = 200;
  MonoTime next = liftd::mono_now();
  for (int i = 0; i < kFrames; ++i) {
    next += 15ms;  // DCP 7.2: 15 ms cycle
    liftd::dcp::MasterFrame f;
    f.comm1 = tx < i0.size() ? static_cast<std::uint8_t>(i0[tx++]) : 0;
    f.comm2 = tx < i0.size() ? static_cast<std::uint8_t>(i0[tx++]) : 0;
    if (m.exchange(f)) ++good;
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(next)));
  }
  EXPECT_GE(good, kFrames * 9 / 10) << "good replies out of " << kFrames;
  const std::string rx(m.channel_rx.begin(), m.channel_rx.end());
  EXPECT_NE(rx.find("\x02\x1CI0KW0100221126"
                    "4"
                    "DE\x03"),
            std::string::npos)
      << rx;
}

TEST(DcpDriveSimTool, ResynchronisesAfterATornFrame) {
  auto pair = liftd::io::PtyPair::create();
  ASSERT_TRUE(pair.ok()) << pair.error().message();
  const std::string slave = pair.value().slave_path();
  Master m{pair.value().take_master(), {}};
  DriveSimProcess sim(slave);
  ASSERT_TRUE(sim.ok());
  ASSERT_TRUE(wait_answering(m)) << "the tool never answered";

  int good = 0;
  for (int i = 0; i < 20; ++i) {
    // Three stray bytes, a pause well over the 1 ms gap, then a whole frame.
    const std::array<std::uint8_t, 3> torn = {0x09, 0x00, 0x80};
    ASSERT_EQ(m.port.write_frame(torn).status, liftd::io::IoStatus::Ok);
    std::this_thread::sleep_for(6ms);
    if (m.exchange(liftd::dcp::MasterFrame{})) ++good;
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_GE(good, 16);
}

}  // namespace
