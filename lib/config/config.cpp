// The plain-data side of the configuration: the default building, problems as text, the DCP3
// speed order and the edit distance behind "did you mean".
#include "config/config.hpp"

#include <algorithm>

namespace liftd::config {

std::vector<Floor> default_floors() {
  // Six floors 3 m apart: a small building for --simulate and the examples.
  std::vector<Floor> floors;
  constexpr int kFloorCount = 6;
  constexpr std::int32_t kFloorHeightMm = 3000;
  for (int i = 0; i < kFloorCount; ++i) floors.push_back({std::to_string(i), i * kFloorHeightMm});
  return floors;
}

std::string to_string(const Problem& problem) {
  return problem.where + ": " + problem.message;
}

std::vector<std::string> dcp3_speeds(int speed_count) {
  // DCP 3.5.3.7: the DCP3 travelling speeds in the order an installation adds them.
  constexpr const auto& kDcp3SpeedOrder = drive::kTravelSpeedNames;
  std::vector<std::string> out;
  for (int i = 0; i < speed_count && i < static_cast<int>(kDcp3SpeedOrder.size()); ++i) {
    out.emplace_back(kDcp3SpeedOrder[static_cast<std::size_t>(i)]);
  }
  return out;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + cost});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace liftd::config
