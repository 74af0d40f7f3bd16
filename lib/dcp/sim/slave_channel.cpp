#include "dcp/sim/slave_channel.hpp"

#include "dcp/channel.hpp"

namespace liftd::dcp::sim {

bool ChannelOutput::push_message(std::uint8_t mode, std::span<const std::uint8_t> body) noexcept {
  const std::size_t need = body.size() + 3;  // STX, mode, ETX
  if (size_ + need > kCapacity) return false;
  auto put = [this](std::uint8_t b) {
    ring_[(head_ + size_) % kCapacity] = b;
    ++size_;
  };
  put(dcp::channel_char::kStx);
  put(mode);
  for (std::uint8_t b : body) put(b);
  put(dcp::channel_char::kEtx);
  return true;
}

bool ChannelOutput::push_raw(std::span<const std::uint8_t> bytes) noexcept {
  if (size_ + bytes.size() > kCapacity) return false;
  for (std::uint8_t b : bytes) {
    ring_[(head_ + size_) % kCapacity] = b;
    ++size_;
  }
  return true;
}

std::uint8_t ChannelOutput::pop() noexcept {
  if (size_ == 0) return dcp::channel_char::kIdle;
  const std::uint8_t b = ring_[head_];
  head_ = (head_ + 1) % kCapacity;
  --size_;
  return b;
}

}  // namespace liftd::dcp::sim
