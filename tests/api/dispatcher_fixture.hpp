// The request handler without a socket, for the API tests and each kind's tests of its own
// commands (tests/<kind>/api): a dispatcher with every command of the daemon, served by a fake
// backend, and the checks several of those tests make of a reply.
#pragma once

#include <gtest/gtest.h>

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"

namespace liftd::api::testing {

/// A connection that records the events sent to it and says how many requests are in flight.
class FakeSession : public SessionControl {
 public:
  void set_watching(bool enable) override { watching_ = enable; }
  bool watching() const override { return watching_; }
  void send_event(std::string line) override { events.push_back(std::move(line)); }
  std::size_t requests_in_flight() const override { return in_flight; }
  std::vector<std::string> events;
  std::size_t in_flight = 1;

 private:
  bool watching_ = false;
};

/// A request the dispatcher must refuse: its line, the error code and the field named ("" =
/// none).
struct RefusedRequest {
  const char* line;
  const char* code;
  const char* field;
};

/// Every command of the daemon (the common ones and, through the registry, every drive kind's)
/// on a dispatcher served by `Fake`: FakeBackend, or a kind's fake derived from it that serves
/// the kind's own commands. The lift's drive kind is the fake's when the fixture is made.
template <typename Fake>
class DispatcherFixture : public ::testing::Test {
 protected:
  DispatcherFixture() { add_every_command(dispatcher_, backend_); }

  /// Handles `line` as `access` and returns the parsed reply (null if none was sent yet).
  nlohmann::json handle(std::string_view line, AccessSet access = {true, true, true}) {
    Peer peer;
    peer.uid = 1000;
    peer.access = access;
    // The reply lands in a member: a deferred responder may answer after handle() returned.
    reply_ = nullptr;
    dispatcher_.handle_line(line, peer, session_, [this](std::string text, bool ok) {
      EXPECT_EQ(text.back(), '\n');
      reply_ = nlohmann::json::parse(text);
      EXPECT_EQ(reply_.at("ok").get<bool>(), ok);
    });
    return reply_;
  }
  static std::string code_of(const nlohmann::json& reply) { return reply.at("error").at("code"); }
  static bool is_ok(const nlohmann::json& reply) { return reply.at("ok").get<bool>(); }

  /// Each request is refused with its code, names its field, and a bad_request's message names
  /// the field too.
  void expect_refused(std::span<const RefusedRequest> requests) {
    for (const RefusedRequest& c : requests) {
      const nlohmann::json reply = handle(c.line);
      ASSERT_FALSE(reply.is_null()) << c.line;
      EXPECT_FALSE(reply.at("ok").get<bool>()) << c.line;
      EXPECT_EQ(code_of(reply), c.code) << c.line;
      if (*c.field != '\0') {
        EXPECT_EQ(reply.at("error").at("field"), c.field) << c.line;
      }
      if (*c.field != '\0' && std::string(c.code) == "bad_request") {
        EXPECT_NE(reply.at("error").at("message").get<std::string>().find(c.field),
                  std::string::npos)
            << "message must name the field: " << c.line;
      }
    }
  }

  /// Each request runs with the access its level gives and no other, and is forbidden to a peer
  /// without access.
  void expect_access_levels(const std::vector<std::pair<std::string, Access>>& requests) {
    const AccessSet only_read{true, false, false};
    const AccessSet only_control{true, true, false};
    const AccessSet only_inputs{true, false, true};
    const AccessSet nothing{false, false, false};
    for (const auto& [line, level] : requests) {
      EXPECT_EQ(is_ok(handle(line, only_read)), level == Access::Read) << line;
      EXPECT_EQ(is_ok(handle(line, only_control)), level != Access::Inputs) << line;
      EXPECT_EQ(is_ok(handle(line, only_inputs)), level != Access::Control) << line;
      EXPECT_EQ(code_of(handle(line, nothing)), "forbidden") << line;
    }
  }

  /// On this lift `own` (a command of the lift's kind) reaches the backend, noted there as `seen`,
  /// and `other` (another kind's) is refused `not_offered` before it: how the registry
  /// (lib/kinds) serves a lift's own kind's commands.
  void expect_only_own_kind_served(std::string_view own, std::string_view other,
                                   std::string_view seen) {
    EXPECT_TRUE(is_ok(handle(own))) << own;
    EXPECT_EQ(code_of(handle(other)), "not_offered") << other;
    ASSERT_EQ(backend_.requests_seen.size(), 1U);
    EXPECT_EQ(backend_.requests_seen[0], seen);
  }

  nlohmann::json reply_;  // declared first: outlives the responders the backend may still hold
  Fake backend_;
  Dispatcher dispatcher_;
  FakeSession session_;
};

}  // namespace liftd::api::testing
