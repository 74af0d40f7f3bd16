// libFuzzer target: one request line through the dispatcher (no socket) of a lift of each drive
// kind in turn, with the shared fake. Every input must give exactly one reply line that is a JSON
// object with "id" and "ok", and never crash. A kind's own commands are refused here: by their
// capability on another kind's lift, on their own kind's because the shared fake serves none;
// each kind's target fuzzes them served (tests/<kind>/api/handler_fuzz.cpp).
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "api/fake_backend.hpp"
#include "api/handler_fuzz.hpp"
#include "drive/drive.hpp"

namespace {

/// A lift of one drive kind: its fake and its dispatcher.
struct Lift {
  liftd::api::testing::FakeBackend backend;
  liftd::api::Dispatcher dispatcher;
};

/// A lift of every registered drive kind (LIFTD_DRIVE_KINDS), in the order of drive::Kind.
std::vector<std::unique_ptr<Lift>> lift_of_every_kind() {
  std::vector<std::unique_ptr<Lift>> lifts;
  for (const std::string_view name : liftd::drive::kKindNames) {
    auto lift = std::make_unique<Lift>();
    lift->backend.status_snapshot.drive_kind = *liftd::drive::parse_kind(name);
    lift->backend.stats_snapshot.drive_kind = lift->backend.status_snapshot.drive_kind;
    lift->dispatcher = liftd::api::testing::every_command_dispatcher(lift->backend);
    lifts.push_back(std::move(lift));
  }
  return lifts;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::unique_ptr<Lift>> lifts = lift_of_every_kind();
  for (const auto& lift : lifts) {
    liftd::api::testing::expect_one_reply(lift->dispatcher, lift->backend, data, size);
  }
  return 0;
}
