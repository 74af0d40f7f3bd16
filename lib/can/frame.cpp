#include "can/frame.hpp"

#include <algorithm>

namespace liftd::can {

Frame make_frame(std::uint32_t id, std::span<const std::uint8_t> bytes) noexcept {
  Frame f;
  f.id = id;
  f.length = static_cast<std::uint8_t>(std::min(bytes.size(), kMaxData));
  std::copy_n(bytes.begin(), f.length, f.data.begin());
  return f;
}

}  // namespace liftd::can
