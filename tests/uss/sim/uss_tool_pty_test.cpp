// tools/uss-drive-sim as a process over a real pty pair: two slaves answer in turn within the
// 20 ms reply delay (USS A 5.2.1.1), an address nobody has stays silent, a mirror telegram comes
// back unchanged (A 5.3), and a broadcast is never answered (A 3). Real time on shared cores:
// counts with margins.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <array>
#include <string>
#include <thread>
#include <vector>

#include "common/mono_time.hpp"
#include "io/pty.hpp"
#include "uss/telegram.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;

class SimProcess {
 public:
  explicit SimProcess(const std::string& device) {
    std::vector<std::string> args = {USS_DRIVE_SIM_PATH, "--device", device,   "--address", "1",
                                     "--address",        "3",        "--quiet"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ok_ = posix_spawn(&pid_, USS_DRIVE_SIM_PATH, nullptr, nullptr, argv.data(), environ) == 0;
  }
  ~SimProcess() {
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

std::vector<std::uint8_t> telegram(std::uint8_t adr, std::vector<std::uint16_t> words) {
  std::array<std::uint8_t, 64> payload{};
  for (std::size_t i = 0; i < words.size(); ++i) liftd::uss::put_word(&payload[2 * i], words[i]);
  std::array<std::uint8_t, 80> out{};
  const auto n = liftd::uss::encode_telegram(adr, {payload.data(), 2 * words.size()}, out);
  return {out.begin(), out.begin() + static_cast<long>(n)};
}

// Sends a telegram and reads a reply of `expect` bytes. The tool answers after its 20 ms reply
// delay; a loaded machine may take longer, and the test counts what the tool answered, so the
// master waits until the reply is certainly not coming (a silent address costs this long).
std::optional<std::vector<std::uint8_t>> exchange(liftd::io::SerialPort& port,
                                                  const std::vector<std::uint8_t>& t,
                                                  std::size_t expect) {
  std::this_thread::sleep_for(2ms);  // start pause and then some
  if (port.write_frame(t).status != liftd::io::IoStatus::Ok) return std::nullopt;
  std::vector<std::uint8_t> reply(expect);
  const auto r = port.read_until(reply, liftd::mono_now() + 300ms);
  if (r.status != liftd::io::IoStatus::Ok) {
    std::this_thread::sleep_for(5ms);
    (void)port.flush_input();
    return std::nullopt;
  }
  return reply;
}

TEST(UssDriveSimTool, AnswersItsSlavesOverAPty) {
  auto pair = liftd::io::PtyPair::create();
  ASSERT_TRUE(pair.ok()) << pair.error().message();
  const std::string slave = pair.value().slave_path();
  auto port = pair.value().take_master();
  SimProcess sim(slave);
  ASSERT_TRUE(sim.ok());
  // Until the tool has started and opened the port, however long a loaded machine takes.
  bool answering = false;
  for (int i = 0; i < 60 && !answering; ++i) {
    answering = exchange(port, telegram(1, {0x1034, 0, 0, 0, 0, 0}), 16).has_value();
  }
  ASSERT_TRUE(answering) << "the tool never answered";
  std::this_thread::sleep_for(50ms);
  (void)port.flush_input();

  int good1 = 0, good3 = 0, silent2 = 0;
  for (int i = 0; i < 30; ++i) {
    // Read P52 (AK 1), STW with control by PLC and OFF1: ready to switch on.
    const auto r1 = exchange(port, telegram(1, {0x1034, 0, 0, 0, 0x047E, 0}), 16);
    if (r1 && liftd::uss::decode_telegram(*r1) && (*r1)[2] == 1 && (*r1)[3] == 0x10 &&
        (*r1)[9] == 0x40) {
      ++good1;
    }
    const auto r3 = exchange(port, telegram(3, {0x1034, 0, 0, 0, 0, 0}), 16);
    if (r3 && liftd::uss::decode_telegram(*r3) && (*r3)[2] == 3) ++good3;
    if (!exchange(port, telegram(2, {0x1034, 0, 0, 0, 0, 0}), 16)) ++silent2;
  }
  EXPECT_GE(good1, 27);
  EXPECT_GE(good3, 27);
  EXPECT_EQ(silent2, 30);

  const auto mirror = telegram(0x40 | 3, {1, 2, 3, 4, 5, 6});
  const auto m = exchange(port, mirror, mirror.size());
  ASSERT_TRUE(m);
  EXPECT_EQ(*m, mirror);
  EXPECT_FALSE(exchange(port, telegram(0x20, {7, 0xFFFF, 0, 0, 0x047E, 0}), 16));
}

}  // namespace
