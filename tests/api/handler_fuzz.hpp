// What the API handler fuzz targets share (tests/api/handler_fuzz.cpp, line_fuzz.cpp and each
// kind's tests/<kind>/api/handler_fuzz.cpp): a session for the dispatcher and the oracle of one
// request line through it, with no socket.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"

namespace liftd::api::testing {

/// A connection whose events must each be one line; aborts otherwise.
class FuzzSession : public SessionControl {
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

/// Every command of the daemon on a dispatcher served by `backend` (FakeBackend or a kind's fake),
/// for a fuzz target's static lift.
inline Dispatcher every_command_dispatcher(FakeBackend& backend) {
  Dispatcher dispatcher;
  add_every_command(dispatcher, backend);
  return dispatcher;
}

/// The input as one request line through `dispatcher`, served by `backend`: it must give exactly
/// one reply line, a JSON object with "id" and "ok", and never crash (aborts otherwise). The
/// first byte picks the peer's access, so forbidden paths are covered too.
inline void expect_one_reply(const Dispatcher& dispatcher, FakeBackend& backend,
                             const std::uint8_t* data, std::size_t size) {
  static FuzzSession session;
  Peer peer;
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
}

/// A fuzz target's whole input step for a lift served by `Fake` (a kind's fake): its static lift
/// takes the input as one request line (expect_one_reply).
template <typename Fake>
int fuzz_one_request(const std::uint8_t* data, std::size_t size) {
  static Fake backend;
  static const Dispatcher dispatcher = every_command_dispatcher(backend);
  expect_one_reply(dispatcher, backend, data, size);
  return 0;
}

}  // namespace liftd::api::testing
