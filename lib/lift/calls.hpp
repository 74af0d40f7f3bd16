// Destinations the car serves in order (a dispatcher adds and cancels them). Fixed capacity.
#pragma once

#include <array>
#include <cstddef>
#include <optional>

#include "lift/floors.hpp"

namespace liftd::lift {

/// Why a call was not queued.
enum class CallError : std::uint8_t {
  None,           ///< queued
  NoSuchFloor,    ///< floor index outside the floor table
  AlreadyQueued,  ///< the floor is already in the queue
  Full,           ///< no room left
};

/// FIFO of destination floors; each floor at most once.
class CallQueue {
 public:
  /// Appends a destination; `floor_count` is the installation's number of floors.
  CallError add(std::size_t floor, std::size_t floor_count) noexcept;
  /// Removes a destination wherever it is; false if it was not queued.
  bool cancel(std::size_t floor) noexcept;
  /// The destination served next.
  std::optional<std::size_t> front() const noexcept;
  /// Drops the front destination (served).
  void pop_front() noexcept;
  /// Whether the floor is queued.
  bool contains(std::size_t floor) const noexcept;
  /// Number of queued destinations.
  std::size_t size() const noexcept { return size_; }
  /// Destination at queue position `index` (< size()).
  std::size_t at(std::size_t index) const noexcept { return floors_[index]; }
  /// Empties the queue.
  void clear() noexcept { size_ = 0; }

 private:
  std::array<std::size_t, kMaxFloors> floors_{};
  std::size_t size_ = 0;
};

}  // namespace liftd::lift
