// libFuzzer target: one request line through the dispatcher (no socket). Every input must give
// exactly one reply line that is a JSON object with "id" and "ok", and never crash.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"

namespace {

class FuzzSession : public liftd::api::SessionControl {
 public:
  void set_watching(bool enable) override { watching_ = enable; }
  bool watching() const override { return watching_; }
  void send_event(std::string line) override {
    if (line.empty() || line.back() != '\n') std::abort();
  }
  std::size_t requests_in_flight() const override { return 1; }

 private:
  bool watching_ = false;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static liftd::api::testing::FakeBackend backend;
  static liftd::api::Dispatcher dispatcher = [] {
    liftd::api::Dispatcher d;
    liftd::api::testing::add_every_command(d, backend);
    return d;
  }();
  static FuzzSession session;
  // The first byte picks the peer's access, so forbidden paths are covered too.
  liftd::api::Peer peer;
  const std::uint8_t mode = size > 0 ? data[0] : 0;
  peer.access = {(mode & 1) != 0, (mode & 2) != 0, (mode & 4) != 0};
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  int replies = 0;
  dispatcher.handle_line(line, peer, session, [&replies](std::string reply, bool ok) {
    ++replies;
    if (reply.empty() || reply.back() != '\n') std::abort();
    const auto parsed = nlohmann::json::parse(reply, nullptr, false);
    if (parsed.is_discarded() || !parsed.contains("id") || parsed.at("ok") != ok) std::abort();
  });
  if (replies != 1) std::abort();
  backend.requests_seen.clear();
  return 0;
}
