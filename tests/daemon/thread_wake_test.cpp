// The io thread's wake-up for a lift's real-time thread (lib/host/lift_core.hpp): a write to the
// eventfd runs the poll at once, without waiting for the fallback timer; the fallback timer runs
// it when the thread says nothing; after stop() nothing runs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>

#include <asio.hpp>

#include "host/lift_core.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;

void bump(int fd) {
  const std::uint64_t one = 1;
  ASSERT_EQ(::write(fd, &one, sizeof one), static_cast<ssize_t>(sizeof one));
}

// Runs the io context until `polls` reaches `want` or `limit` passes (a limit far beyond any
// machine's delay: the test judges which path ran, not how fast).
void run_until(asio::io_context& io, const int& polls, int want, std::chrono::seconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (polls < want && std::chrono::steady_clock::now() < until) io.run_one_for(100ms);
}

TEST(ThreadWake, NewsFromTheThreadRunsThePollWithoutTheFallback) {
  asio::io_context io;
  ThreadWake wake(io, 1h);  // the fallback cannot be what runs the poll
  int polls = 0;
  wake.start([&] { ++polls; });
  bump(wake.fd());
  run_until(io, polls, 1, 10s);
  EXPECT_EQ(polls, 1);
  // Several bumps before the io thread looks are one poll: the eventfd counts, one read resets.
  bump(wake.fd());
  bump(wake.fd());
  bump(wake.fd());
  run_until(io, polls, 2, 10s);
  io.poll();  // anything else already due
  EXPECT_EQ(polls, 2);
  wake.stop();
}

TEST(ThreadWake, TheFallbackPollsAThreadThatSaysNothing) {
  asio::io_context io;
  ThreadWake wake(io, 1ms);
  int polls = 0;
  wake.start([&] { ++polls; });
  run_until(io, polls, 3, 10s);
  EXPECT_GE(polls, 3);
  wake.stop();
}

TEST(ThreadWake, NothingRunsAfterStop) {
  asio::io_context io;
  ThreadWake wake(io, 1ms);
  int polls = 0;
  wake.start([&] { ++polls; });
  EXPECT_TRUE(wake.running());
  wake.stop();
  EXPECT_FALSE(wake.running());
  bump(wake.fd());
  io.run_for(20ms);  // the cancelled waits complete with an error and run nothing
  EXPECT_EQ(polls, 0);
}

}  // namespace
}  // namespace liftd::daemon
