// The hand-built telegrams, the fake-clock Harness and the slave configs the USS slave tests share.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "uss/sim/uss_slave_sim.hpp"
#include "uss/timing.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;
using liftd::uss::PkwLength;
using liftd::uss::sim::UssDriveState;
using liftd::uss::sim::UssReply;
using liftd::uss::sim::UssReplyFault;
using liftd::uss::sim::UssSlaveConfig;
using liftd::uss::sim::UssSlaveSim;
using Bytes = std::vector<std::uint8_t>;
using Words = std::vector<std::uint16_t>;

constexpr std::uint32_t kBaud = 38400;

inline Bytes telegram(std::uint8_t adr, const Words& words) {
  Bytes b = {0x02, static_cast<std::uint8_t>(2 * words.size() + 2), adr};
  for (const auto w : words) {
    b.push_back(static_cast<std::uint8_t>(w >> 8));
    b.push_back(static_cast<std::uint8_t>(w & 0xFF));
  }
  std::uint8_t bcc = 0;
  for (const auto x : b) bcc ^= x;
  b.push_back(bcc);
  return b;
}

inline std::string hex(const Bytes& b) {
  std::string s;
  char buf[4];
  for (const auto x : b) {
    std::snprintf(buf, sizeof buf, "%02X ", x);
    s += buf;
  }
  return s;
}

struct Harness {
  MonoTime now{std::chrono::seconds(10)};
  UssSlaveSim sim;
  UssReply last{};
  MonoTime request_end{};

  explicit Harness(const UssSlaveConfig& c) : sim(c, kBaud, MonoTime{std::chrono::seconds(10)}) {}

  void send(const Bytes& bytes, std::chrono::nanoseconds pause = 5ms,
            std::optional<std::size_t> parity_at = std::nullopt) {
    now += pause;
    const auto tz = liftd::uss::character_time(kBaud);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      now += tz;
      liftd::uss::RxChar c{bytes[i], liftd::uss::LineError::None};
      if (parity_at && *parity_at == i) c.error = liftd::uss::LineError::Parity;
      sim.on_char(c, now);
    }
    request_end = now;
  }
  // Waits up to 40 ms in 50 us steps for a reply.
  std::optional<Bytes> wait_reply() {
    for (int i = 0; i < 800; ++i) {
      now += 50us;
      sim.on_time(now);
      if (sim.take_reply(now, last)) {
        now = last.send_at + liftd::uss::transmission_time(kBaud, last.size);
        return Bytes(last.bytes.begin(), last.bytes.begin() + static_cast<long>(last.size));
      }
    }
    return std::nullopt;
  }
  std::optional<Bytes> exchange(const Bytes& bytes) {
    send(bytes);
    return wait_reply();
  }
  // The reply's payload words; checks frame, LGE and BCC.
  Words words(std::uint8_t adr, const Words& request) {
    const auto r = exchange(telegram(adr, request));
    if (!r) {
      ADD_FAILURE() << "no reply";
      return {};
    }
    return payload_words(*r);
  }
  static Words payload_words(const Bytes& r) {
    EXPECT_GE(r.size(), 4U);
    EXPECT_EQ(r[0], 0x02);
    EXPECT_EQ(r[1], r.size() - 2);
    std::uint8_t bcc = 0;
    for (std::size_t i = 0; i + 1 < r.size(); ++i) bcc ^= r[i];
    EXPECT_EQ(bcc, r.back()) << hex(r);
    Words w;
    for (std::size_t i = 3; i + 2 < r.size(); i += 2) {
      w.push_back(static_cast<std::uint16_t>(r[i] << 8 | r[i + 1]));
    }
    return w;
  }
  std::vector<std::string_view> violations() {
    std::array<liftd::uss::sim::UssViolation, 64> v{};
    const std::size_t n = sim.take_violations(v);
    std::vector<std::string_view> out;
    for (std::size_t i = 0; i < n; ++i) out.push_back(v[i].rule);
    return out;
  }
};

inline UssSlaveConfig config(liftd::uss::PkwLength pkw, std::uint8_t pzd,
                             std::uint8_t address = 5) {
  UssSlaveConfig c;
  c.address = address;
  c.pkw = pkw;
  c.pzd_words = pzd;
  c.telegram_timeout = 0s;
  return c;
}

constexpr std::uint16_t pke(unsigned ak, unsigned pnu, bool toggle = false) {
  return static_cast<std::uint16_t>(ak << 12 | (toggle ? 1U << 11 : 0U) | pnu);
}

}  // namespace
