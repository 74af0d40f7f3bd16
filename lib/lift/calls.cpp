#include "lift/calls.hpp"

namespace liftd::lift {

CallError CallQueue::add(std::size_t floor, std::size_t floor_count) noexcept {
  if (floor >= floor_count) return CallError::NoSuchFloor;
  if (contains(floor)) return CallError::AlreadyQueued;
  if (size_ == floors_.size()) return CallError::Full;
  floors_[size_++] = floor;
  return CallError::None;
}

CallError CallQueue::insert(std::size_t index, std::size_t floor,
                            std::size_t floor_count) noexcept {
  if (floor >= floor_count) return CallError::NoSuchFloor;
  if (index > size_) return CallError::BadPosition;
  if ((index > 0 && floors_[index - 1] == floor) || (index < size_ && floors_[index] == floor)) {
    return CallError::TwiceInARow;
  }
  if (size_ == floors_.size()) return CallError::Full;
  for (std::size_t j = size_; j > index; --j) floors_[j] = floors_[j - 1];
  floors_[index] = floor;
  ++size_;
  return CallError::None;
}

CallError CallQueue::set(std::span<const std::uint8_t> floors, std::size_t floor_count,
                         bool keep_front) noexcept {
  const bool keep = keep_front && size_ > 0;
  // A list that starts with the kept floor means that same stop.
  if (keep && !floors.empty() && floors.front() == floors_[0]) floors = floors.subspan(1);
  const std::size_t kept = keep ? 1 : 0;
  if (floors.size() + kept > floors_.size()) return CallError::Full;
  for (std::size_t i = 0; i < floors.size(); ++i) {
    if (floors[i] >= floor_count) return CallError::NoSuchFloor;
    const std::size_t before = i > 0 ? floors[i - 1] : (keep ? floors_[0] : floor_count);
    if (floors[i] == before) return CallError::TwiceInARow;
  }
  for (std::size_t i = 0; i < floors.size(); ++i) floors_[kept + i] = floors[i];
  size_ = kept + floors.size();
  return CallError::None;
}

DroppedCalls CallQueue::drop() noexcept {
  DroppedCalls dropped;
  for (std::size_t i = 0; i < size_; ++i) dropped.floors.set(floors_[i]);
  size_ = 0;
  return dropped;
}

bool CallQueue::cancel(std::size_t floor) noexcept {
  for (std::size_t i = 0; i < size_; ++i) {
    if (floors_[i] != floor) continue;
    for (std::size_t j = i + 1; j < size_; ++j) floors_[j - 1] = floors_[j];
    --size_;
    return true;
  }
  return false;
}

std::optional<std::size_t> CallQueue::front() const noexcept {
  if (size_ == 0) return std::nullopt;
  return floors_[0];
}

void CallQueue::pop_front() noexcept {
  static_cast<void>(cancel(floors_[0]));
}

bool CallQueue::contains(std::size_t floor) const noexcept {
  for (std::size_t i = 0; i < size_; ++i) {
    if (floors_[i] == floor) return true;
  }
  return false;
}

}  // namespace liftd::lift
