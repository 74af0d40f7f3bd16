#include "uss/pzd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace liftd::uss {
namespace {

// Appendix: PZD words 1, 4 and 5 have their own bit masks b, c, d; PZD 16 is never taken over.
constexpr std::size_t kBroadcastWords = 15;
constexpr std::size_t kPzd1 = 1;
constexpr std::size_t kPzd4 = 4;
constexpr std::size_t kPzd5 = 5;
constexpr std::uint16_t kBroadcastFlag = 0x0001;  // word a bit 0

std::uint16_t merge(std::uint16_t current, std::uint16_t received, std::uint16_t mask) {
  return static_cast<std::uint16_t>((current & ~mask) | (received & mask));
}

}  // namespace

std::int16_t Normalisation::to_raw(double v) const noexcept {
  if (full_scale == 0.0 || !std::isfinite(v)) return 0;
  const double raw = std::round(v / full_scale * static_cast<double>(raw_full_scale));
  if (std::isnan(raw)) return 0;
  if (raw >= std::numeric_limits<std::int16_t>::max())
    return std::numeric_limits<std::int16_t>::max();
  if (raw <= std::numeric_limits<std::int16_t>::min())
    return std::numeric_limits<std::int16_t>::min();
  return static_cast<std::int16_t>(raw);
}

double Normalisation::from_raw(std::int16_t raw) const noexcept {
  if (raw_full_scale == 0) return 0.0;
  return static_cast<double>(raw) * full_scale / static_cast<double>(raw_full_scale);
}

void encode_broadcast_enable(const BroadcastEnable& be, Pkw& pkw) noexcept {
  // Appendix Fig. 2.5.1.6: the PKW area carries words a, b, c, d instead of PKE IND PWE1 PWE2.
  pkw = Pkw{};
  pkw.set_pke(be.word_a());
  pkw.ind = be.mask_pzd1;
  pkw.pwe[0] = be.mask_pzd4;
  pkw.pwe[1] = be.mask_pzd5;
  pkw.pwe_count = 2;
}

BroadcastEnable decode_broadcast_enable(const Pkw& pkw) noexcept {
  BroadcastEnable be;
  const std::uint16_t a = pkw.pke();
  be.enable = (a & kBroadcastFlag) != 0;
  be.pzd_words = static_cast<std::uint16_t>(a & ~kBroadcastFlag);
  be.mask_pzd1 = pkw.ind;
  be.mask_pzd4 = pkw.pwe_count > 0 ? pkw.pwe[0] : std::uint16_t{0};
  be.mask_pzd5 = pkw.pwe_count > 1 ? pkw.pwe[1] : std::uint16_t{0};
  return be;
}

void apply_broadcast(const BroadcastEnable& be, std::span<const std::uint16_t> received,
                     std::span<std::uint16_t> current) noexcept {
  if (!be.enable) return;  // appendix example 1/2: the flag must be set
  const std::size_t n = std::min({kBroadcastWords, received.size(), current.size()});
  for (std::size_t k = 1; k <= n; ++k) {
    if ((be.pzd_words & pzd_word_bit(static_cast<unsigned>(k))) == 0) continue;
    std::uint16_t& cur = current[k - 1];
    const std::uint16_t in = received[k - 1];
    switch (k) {
      case kPzd1:
        cur = merge(cur, in, be.mask_pzd1);
        break;
      case kPzd4:
        cur = merge(cur, in, be.mask_pzd4);
        break;
      case kPzd5:
        cur = merge(cur, in, be.mask_pzd5);
        break;
      default:
        cur = in;
        break;
    }
  }
}

}  // namespace liftd::uss
