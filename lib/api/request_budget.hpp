// How many requests the io thread answers per second over all clients (api.max_requests_per_s).
// A client beyond it waits for its turn, nothing is refused; with each turn at most a few lines
// (lib/api/server.cpp), every waiting client gets an equal share. It bounds the CPU the API can
// take from the rest of the board: on a board whose CPUs the API saturated, the tty's
// flip-buffer worker, a normal-priority kernel thread that carries every byte the drive sends,
// waited for a CPU until replies missed their deadline and the link faulted (DCP 7.3;
// docs/architecture.md, "What the cycle may wait for"). Sans-I/O: the caller passes the time.
#pragma once

#include <chrono>
#include <cstddef>

namespace liftd::api {

class RequestBudget {
 public:
  using Clock = std::chrono::steady_clock;

  /// `per_second` requests a second at most; 0 = no limit. It holds at most a tenth of a
  /// second's worth (never less than `min_burst`), so a burst after a quiet time is that big.
  RequestBudget(double per_second, std::size_t min_burst, Clock::time_point now);

  /// Takes one request's share: false when there is none left before next_at().
  bool take(Clock::time_point now);
  /// When take() succeeds again (`now` while there is budget, or no limit).
  Clock::time_point next_at(Clock::time_point now) const;
  /// A new rate from a reload; what was saved stays (up to the new burst).
  void set_rate(double per_second, Clock::time_point now);

  double per_second() const { return per_second_; }
  bool limited() const { return per_second_ > 0; }

 private:
  double per_second_ = 0;
  std::size_t min_burst_ = 1;
  Clock::duration interval_{};   ///< 1 / per_second_
  Clock::duration tolerance_{};  ///< the burst less one request, in time
  Clock::time_point due_{};      ///< when the budget is full again
};

}  // namespace liftd::api
