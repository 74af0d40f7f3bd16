// Helpers shared by the DCP channel and engine tests.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace liftd::dcp::test {

/// The bytes of a string literal, e.g. bytes("I0") == {0x49, 0x30}.
inline std::vector<std::uint8_t> bytes(std::string_view text) {
  return {text.begin(), text.end()};
}

}  // namespace liftd::dcp::test
