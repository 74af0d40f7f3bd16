// The request budget (api.max_requests_per_s) on a fake clock.
#include "api/request_budget.hpp"

#include <gtest/gtest.h>

#include <chrono>

namespace liftd::api {
namespace {

using namespace std::chrono_literals;
using Clock = RequestBudget::Clock;
const Clock::time_point t0{};

TEST(RequestBudget, NoLimitAlwaysHasBudget) {
  RequestBudget budget(0, 4, t0);
  EXPECT_FALSE(budget.limited());
  for (int i = 0; i < 100000; ++i) ASSERT_TRUE(budget.take(t0));
  EXPECT_EQ(budget.next_at(t0), t0);
}

TEST(RequestBudget, HoldsATenthOfASecondAndRefillsAtTheRate) {
  struct Case {
    double rate;
    std::size_t min_burst;
    int burst;                 // takes that succeed at once
    Clock::duration per_take;  // 1 / rate
  };
  const Case cases[] = {
      {5000, 4, 500, 200us},                    // a tenth of a second's worth
      {100, 4, 10, 10ms},    {20, 4, 4, 50ms},  // never less than one client's turn
      {1, 4, 4, 1s},         {0.5, 1, 1, 2s},
  };
  for (const Case& c : cases) {
    RequestBudget budget(c.rate, c.min_burst, t0);
    int taken = 0;
    while (budget.take(t0)) ++taken;
    EXPECT_EQ(taken, c.burst) << c.rate << "/s";
    EXPECT_EQ(budget.next_at(t0), t0 + c.per_take) << c.rate << "/s";
    EXPECT_FALSE(budget.take(t0 + c.per_take - 1us)) << c.rate << "/s";
    EXPECT_TRUE(budget.take(t0 + c.per_take)) << c.rate << "/s";
    EXPECT_FALSE(budget.take(t0 + c.per_take)) << c.rate << "/s";
  }
}

TEST(RequestBudget, OverASecondAnswersTheRateAndNoMore) {
  RequestBudget budget(1000, 4, t0);
  int taken = 0;
  for (auto t = t0; t < t0 + 1s; t += 100us) {
    while (budget.take(t)) ++taken;
  }
  // The burst it started with (100) plus one second's refill less the last step.
  EXPECT_GE(taken, 1000 + 100 - 1);
  EXPECT_LE(taken, 1000 + 100);
}

TEST(RequestBudget, AReloadChangesTheRateAndKeepsNoMoreThanTheNewBurst) {
  RequestBudget budget(1000, 4, t0);  // holds 100
  budget.set_rate(50, t0);            // holds 5 now
  int taken = 0;
  while (budget.take(t0)) ++taken;
  EXPECT_EQ(taken, 5);
  EXPECT_EQ(budget.next_at(t0), t0 + 20ms);
  budget.set_rate(0, t0);
  EXPECT_TRUE(budget.take(t0));
  EXPECT_EQ(budget.next_at(t0), t0);
}

}  // namespace
}  // namespace liftd::api
