// Destinations the car serves in order (a dispatcher adds and cancels them). Fixed capacity.
#pragma once

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "lift/floors.hpp"

namespace liftd::lift {

/// Why a call was not queued.
enum class CallError : std::uint8_t {
  None,           ///< queued
  NoSuchFloor,    ///< floor index outside the floor table
  AlreadyQueued,  ///< the floor is already in the queue (add)
  Full,           ///< no room left
  BadPosition,    ///< insert: a position beyond the end of the queue
  TwiceInARow,    ///< the same floor twice in a row: the car is there after the first
};

/// The floors a queue held when liftd emptied it (event calls_dropped).
struct DroppedCalls {
  std::bitset<kMaxFloors> floors;  ///< each floor that was queued, once
};

/// A change of the calls queue (API `calls`), io thread -> controller.
struct CallCommand {
  enum class Op : std::uint8_t { Add, Cancel, Insert, Set };
  Op op = Op::Add;
  std::size_t floor = 0;                          ///< Add, Cancel, Insert
  std::optional<std::size_t> position;            ///< Insert: where (0: first; none: the end)
  std::array<std::uint8_t, kMaxFloors> floors{};  ///< Set: the new queue, first served first
  std::size_t count = 0;                          ///< Set: how many of `floors`

  /// `calls add` of `floor`.
  static CallCommand adding(std::size_t floor) noexcept { return {Op::Add, floor, {}, {}, 0}; }
  /// `calls cancel` of `floor`.
  static CallCommand cancelling(std::size_t floor) noexcept {
    return {Op::Cancel, floor, {}, {}, 0};
  }
};

/// Destination floors served in order. `add` queues a floor once; `insert` and `set` let the
/// dispatcher plan a floor more than once (0 -> 1 -> 0), never twice in a row. Each change either
/// applies whole or changes nothing.
class CallQueue {
 public:
  /// Appends a destination; `floor_count` is the installation's number of floors.
  CallError add(std::size_t floor, std::size_t floor_count) noexcept;
  /// Puts `floor` at queue position `index` (0: first, size(): last).
  CallError insert(std::size_t index, std::size_t floor, std::size_t floor_count) noexcept;
  /// Replaces the queue by `floors` (first served first); empty empties it. With `keep_front`
  /// the floor now first stays first (a travel already heads for it): `floors` follow it, and a
  /// leading repeat of it is taken as that same stop.
  CallError set(std::span<const std::uint8_t> floors, std::size_t floor_count,
                bool keep_front) noexcept;
  /// Removes the first occurrence of a destination; false if it was not queued.
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
  /// Empties the queue and says which floors it held.
  DroppedCalls drop() noexcept;

 private:
  std::array<std::size_t, kMaxFloors> floors_{};
  std::size_t size_ = 0;
};

}  // namespace liftd::lift
