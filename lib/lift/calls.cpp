#include "lift/calls.hpp"

namespace liftd::lift {

CallError CallQueue::add(std::size_t floor, std::size_t floor_count) noexcept {
  if (floor >= floor_count) return CallError::NoSuchFloor;
  if (contains(floor)) return CallError::AlreadyQueued;
  if (size_ == floors_.size()) return CallError::Full;
  floors_[size_++] = floor;
  return CallError::None;
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
