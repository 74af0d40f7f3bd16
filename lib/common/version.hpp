// The liftd version, set by CMake from the project version.
#pragma once

#include <string_view>

namespace liftd {

/// "MAJOR.MINOR.PATCH"
inline constexpr std::string_view kVersion = LIFTD_VERSION;

}  // namespace liftd
