// tools/dcp-drive-sim against a small master loop over a real pty pair: frames answered in
// time, the channel works end to end, a torn frame is resynchronised by the gap, and with
// --encoder the tool is the shaft's CAN encoder on a Unix endpoint.
// Real time on shared cores: asserts on counts with generous margins.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "can/encoder.hpp"
#include "can/socket.hpp"
#include "common/mono_time.hpp"
#include "dcp/frame.hpp"
#include "io/pty.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;

class DriveSimProcess {
 public:
  explicit DriveSimProcess(const std::string& device, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {DCP_DRIVE_SIM_PATH, "--device", device, "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
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

/// Connects to the tool's encoder endpoint, however long a loaded machine takes to start it.
std::optional<liftd::can::CanSocket> connect_encoder(const std::string& endpoint) {
  const MonoTime until = liftd::mono_now() + 20s;
  while (liftd::mono_now() < until) {
    if (auto s = liftd::can::CanSocket::open(endpoint, {}); s) return std::move(s.value());
    std::this_thread::sleep_for(20ms);
  }
  return std::nullopt;
}

/// The next data frame on `socket`, waiting up to 5 s; nullopt when none came.
std::optional<liftd::can::Frame> next_frame(liftd::can::CanSocket& socket) {
  const MonoTime until = liftd::mono_now() + 5s;
  while (liftd::mono_now() < until) {
    const auto got = socket.read();
    if (got.kind == liftd::can::Received::Kind::Frame) return got.frame;
    if (got.kind != liftd::can::Received::Kind::Nothing) return std::nullopt;
    pollfd fd{socket.fd(), POLLIN, 0};
    (void)::poll(&fd, 1, 50);
  }
  return std::nullopt;
}

TEST(DcpDriveSimTool, IsTheShaftEncoderOnAUnixCanEndpointInTheDocumentedFormat) {
  auto pair = liftd::io::PtyPair::create();
  ASSERT_TRUE(pair.ok()) << pair.error().message();
  const std::string slave = pair.value().slave_path();
  Master m{pair.value().take_master(), {}};
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("liftd-encoder-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string endpoint = "unix:" + (dir / "encoder.sock").string();
  DriveSimProcess sim(slave, {"--position-mm", "-1234", "--encoder", endpoint});
  ASSERT_TRUE(sim.ok());

  // The format --help promises: id 0x190, four bytes little endian, two's complement, 1 mm per
  // count: liftd's position.can_* defaults with can_signed true.
  liftd::can::EncoderFormat format;
  format.is_signed = true;
  for (int reader = 0; reader < 2; ++reader) {  // a second reader after the first left
    auto encoder = connect_encoder(endpoint);
    ASSERT_TRUE(encoder.has_value()) << "no encoder on " << endpoint;
    for (int i = 0; i < 3; ++i) {
      const auto frame = next_frame(*encoder);
      ASSERT_TRUE(frame.has_value()) << "reader " << reader << " frame " << i;
      EXPECT_EQ(frame->id, 0x190u);
      EXPECT_EQ(frame->length, 4u);
      EXPECT_EQ(liftd::can::decode_position(format, *frame), -1234) << "reader " << reader;
    }
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
