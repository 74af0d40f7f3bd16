// travel-bench: floor-to-floor times and landing accuracy, DCP4 against DCP3, with the real
// DcpController against the drive simulator at its default parameters, in process on a fake
// clock (tests/dcp/control/controller_rig.hpp). Times run from the cycle that takes the travel
// command to the first reply with S1 = 0 (DCP 9.1.4: travel over), so they are simulated
// seconds at the 15 ms cycle's resolution, independent of the machine running the program.
//
//   travel-bench          print both tables
//   travel-bench --help   this text
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <vector>

#include "dcp/control/controller_rig.hpp"

namespace {

using liftd::control::CommandReply;
using liftd::control::ReplyCode;
using liftd::control::TravelCommand;
using liftd::control::testing::Rig;
namespace dcp = liftd::dcp;
namespace sb = liftd::dcp::status_bit;
using namespace std::chrono_literals;

struct TravelResult {
  bool ok = false;
  double seconds = 0.0;   ///< travel command to S1 = 0
  double error_mm = 0.0;  ///< car position minus the level, once stationary
  dcp::Speed speed{};     ///< speed message sent for the travel
};

/// One travel from the car's place to `floor`, timed on the rig's log.
TravelResult travel(Rig& rig, std::size_t floor) {
  TravelResult result;
  const std::size_t first = rig.log.size();
  rig.post(TravelCommand{floor, std::nullopt, std::nullopt, false}, 1);
  bool started = false;
  std::optional<std::size_t> ended;
  for (int i = 0; i < 8000 && !ended; ++i) {  // 120 s of cycles at most
    rig.cycle();
    const auto& r = rig.log.back();
    if (!r.reply) continue;
    const bool s1 = (*r.reply & sb::kTravelActive) != 0;
    if (s1) started = true;
    if (started && !s1) ended = rig.log.size() - 1;
  }
  if (!ended) return result;
  result.seconds = std::chrono::duration<double>(rig.log[*ended].at - rig.log[first].at).count();
  rig.run_until([&] { return rig.idle() && rig.sim.stationary(); }, 10s);
  result.error_mm = rig.sim.position_mm() - static_cast<double>(rig.controller.floors_mm()[floor]);
  for (std::size_t i = first; i < rig.log.size(); ++i) {
    if ((rig.log[i].frame[0] & 0x0F) == 0x9) {  // DCP 3.5: the speed message 1001
      result.speed = static_cast<dcp::Speed>((rig.log[i].frame[1] << 8) | rig.log[i].frame[2]);
      break;
    }
  }
  rig.replies.clear();
  result.ok = true;
  return result;
}

const char* speed_name(dcp::Speed speed) {
  switch (speed) {
    case dcp::Speed::V4:
      return "V4";
    case dcp::Speed::V3:
      return "V3";
    case dcp::Speed::V0:
      return "V0";
    default:
      return "?";
  }
}

struct DialectFigures {
  std::vector<TravelResult> hops;  ///< 1, 2 and 5 floors up from floor 0
  std::vector<double> errors_mm;   ///< every ordered floor pair
};

std::optional<DialectFigures> measure(dcp::Protocol protocol) {
  DialectFigures figures;
  Rig rig(protocol);
  if (!rig.warm_up()) return std::nullopt;
  const auto floors = liftd::control::testing::six_floors();
  for (std::size_t n : {1U, 2U, 5U}) {
    rig.place_at(floors[0]);
    const TravelResult r = travel(rig, n);
    if (!r.ok) return std::nullopt;
    figures.hops.push_back(r);
  }
  for (std::size_t from = 0; from < floors.size(); ++from) {
    for (std::size_t to = 0; to < floors.size(); ++to) {
      if (from == to) continue;
      rig.place_at(floors[from]);
      const TravelResult r = travel(rig, to);
      if (!r.ok) return std::nullopt;
      figures.errors_mm.push_back(r.error_mm);
    }
  }
  std::sort(figures.errors_mm.begin(), figures.errors_mm.end());
  return figures;
}

/// Rounded to 0.01 mm, without printing "-0.00".
double tidy(double mm) {
  const double r = std::round(mm * 100.0) / 100.0;
  return r == 0.0 ? 0.0 : r;
}

double median(const std::vector<double>& sorted) {
  const std::size_t n = sorted.size();
  return n % 2 == 1 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) {
    const bool help = std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0;
    std::fputs(
        "usage: travel-bench\n"
        "Floor-to-floor times (travel command to S1 = 0) for 1, 2 and 5 floors and the landing\n"
        "error over every floor pair, DCP4 against DCP3, DcpController against the drive\n"
        "simulator's defaults, six floors 3 m apart, simulated time on a fake clock.\n",
        help ? stdout : stderr);
    return help ? 0 : 2;
  }
  const auto d4 = measure(dcp::Protocol::Dcp4);
  const auto d3 = measure(dcp::Protocol::Dcp3);
  if (!d4 || !d3) {
    std::fputs("travel-bench: a travel did not complete\n", stderr);
    return 1;
  }
  std::printf("Floor-to-floor time, travel command to S1 = 0 (s), floors 3 m apart\n");
  std::printf("%-8s %-8s %-8s %-8s %-8s %s\n", "floors", "metres", "DCP4", "DCP3", "DCP3 v",
              "DCP4 saves");
  const int counts[] = {1, 2, 5};
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& a = d4->hops[i];
    const auto& b = d3->hops[i];
    std::printf("%-8d %-8d %-8.2f %-8.2f %-8s %.2f s (%.0f %%)\n", counts[i], counts[i] * 3,
                a.seconds, b.seconds, speed_name(b.speed), b.seconds - a.seconds,
                100.0 * (b.seconds - a.seconds) / b.seconds);
  }
  std::printf("\nLanding error over all %zu ordered floor pairs (mm, + above the level)\n",
              d4->errors_mm.size());
  std::printf("%-8s %-8s %-8s %-8s %s\n", "dialect", "min", "median", "max", "max |error|");
  for (const auto* f : {&*d4, &*d3}) {
    const auto& e = f->errors_mm;
    const double worst = std::max(std::fabs(e.front()), std::fabs(e.back()));
    std::printf("%-8s %-8.2f %-8.2f %-8.2f %.2f\n", f == &*d4 ? "DCP4" : "DCP3", tidy(e.front()),
                tidy(median(e)), tidy(e.back()), tidy(worst));
  }
  return 0;
}
