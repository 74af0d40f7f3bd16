// The requests every lift's io thread keeps until its controller answers (lib/host/lift_core.hpp):
// one reply answers one request, an ok reply goes through the request's own completion, every
// other reply code is the API's error of the same meaning, tags stay clear of 0 and of a
// controller's own, and a request the controller never answers fails at its deadline.
#include <gtest/gtest.h>

#include <optional>
#include <string_view>
#include <vector>

#include "host/lift_core.hpp"
#include "lift/rules.hpp"

namespace liftd::daemon {
namespace {

using std::chrono::milliseconds;

/// A controller's reply as every controller has it (the DCP's also carries `extended`).
struct Reply {
  std::uint32_t tag = 0;
  lift::ReplyCode code = lift::ReplyCode::Ok;
  std::string_view detail;
  std::optional<std::size_t> floor;
  bool extended = false;
};

/// Collects the results a responder was given.
struct Answers {
  api::Responder responder() {
    return [this](api::Result r) { results.push_back(std::move(r)); };
  }
  std::vector<api::Result> results;
};

TEST(PendingReplies, EachReplyCodeIsTheApiErrorOfTheSameMeaning) {
  const struct {
    lift::ReplyCode code;
    api::ErrorCode api;
  } cases[] = {
      {lift::ReplyCode::NotReady, api::ErrorCode::NotReady},
      {lift::ReplyCode::Busy, api::ErrorCode::Busy},
      {lift::ReplyCode::BadRequest, api::ErrorCode::BadRequest},
      {lift::ReplyCode::Fault, api::ErrorCode::Fault},
      {lift::ReplyCode::Timeout, api::ErrorCode::Timeout},
  };
  for (const auto& c : cases) {
    PendingReplies<Reply> pending;
    Answers answers;
    bool completion_ran = false;
    const std::uint32_t tag =
        pending.add(answers.responder(), milliseconds(100), [&](const Reply&) {
          completion_ran = true;
          return api::Result::ok();
        });
    ASSERT_TRUE(pending.answer(Reply{tag, c.code, "why", std::nullopt, false}));
    ASSERT_EQ(answers.results.size(), 1U);
    ASSERT_FALSE(answers.results[0].is_ok());
    EXPECT_EQ(answers.results[0].error().code, c.api) << static_cast<int>(c.code);
    EXPECT_EQ(answers.results[0].error().message, "why");
    EXPECT_FALSE(completion_ran) << "a refusal is never a completion's result";
  }
}

TEST(PendingReplies, AnOkReplyGoesThroughTheRequestsCompletionOrShowsDetailFloorAndExtended) {
  PendingReplies<Reply> pending;
  Answers answers;
  const std::uint32_t plain = pending.add(answers.responder(), milliseconds(100));
  const std::uint32_t own = pending.add(answers.responder(), milliseconds(100), [](const Reply&) {
    return api::Result::ok({{"own", true}});
  });
  ASSERT_TRUE(pending.answer(Reply{plain, lift::ReplyCode::Ok, "target extended", 3, true}));
  ASSERT_TRUE(pending.answer(Reply{own, lift::ReplyCode::Ok, {}, std::nullopt, false}));
  ASSERT_EQ(answers.results.size(), 2U);
  EXPECT_EQ(answers.results[0].value(),
            (nlohmann::json{{"detail", "target extended"}, {"extended", true}, {"floor", 3}}));
  EXPECT_EQ(answers.results[1].value(), (nlohmann::json{{"own", true}}));
  // Answered once: a second reply with the same tag finds nobody waiting.
  EXPECT_FALSE(pending.answer(Reply{plain, lift::ReplyCode::Ok, {}, std::nullopt, false}));
  EXPECT_EQ(answers.results.size(), 2U);
}

TEST(PendingReplies, TagsAreNeverZeroNorAControllersOwn) {
  PendingReplies<Reply> pending;
  Answers answers;
  std::uint32_t last = 0;
  for (int i = 0; i < 1000; ++i) {
    last = pending.add(answers.responder(), milliseconds(100));
    ASSERT_NE(last, 0U);
    ASSERT_LT(last, kFirstControllerTag);
    ASSERT_TRUE(pending.complete(last, api::Result::ok()));
  }
  EXPECT_EQ(last, 1000U);
}

TEST(PendingReplies, ARequestNeverAnsweredFailsAtItsDeadlineOnly) {
  PendingReplies<Reply> pending;
  Answers answers;
  const std::uint32_t tag = pending.add(answers.responder(), milliseconds(100));
  pending.expire(milliseconds(100), "stalled");
  EXPECT_TRUE(answers.results.empty()) << "not before its deadline";
  EXPECT_TRUE(pending.waiting(tag));
  pending.expire(milliseconds(101), "stalled");
  ASSERT_EQ(answers.results.size(), 1U);
  EXPECT_EQ(answers.results[0].error().code, api::ErrorCode::Internal);
  EXPECT_EQ(answers.results[0].error().message, "stalled");
  EXPECT_FALSE(pending.waiting(tag));
  // Its late reply finds nobody waiting.
  EXPECT_FALSE(pending.answer(Reply{tag, lift::ReplyCode::Ok, {}, std::nullopt, false}));
}

}  // namespace
}  // namespace liftd::daemon
