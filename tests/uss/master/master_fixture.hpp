// The one-slave bus, idle reply and PKW read request the USS master tests (master*_test.cpp) share.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "bus_harness.hpp"

namespace liftd::uss {
namespace {

using namespace std::chrono_literals;
using testing::Bus;
using testing::Bytes;
using testing::make_reply;
using testing::parse_request;
using testing::reply_pkw;
using testing::Sent;

inline MasterConfig one_slave(std::uint32_t baud = 38400, PkwLength pkw = PkwLength::Three,
                              std::uint8_t pzd = 2) {
  MasterConfig c;
  c.baud = baud;
  c.slaves = {SlaveConfig{5, pkw, pzd}};
  c.polling_list = {5};
  c.mirror_at_start = false;
  return c;
}

// Answers a poll of slave `address` (PKW 3 words, 2 PZD) with "keine Antwort" and ZSW/HIW.
inline Bytes idle_reply(std::uint8_t address, PkwLength len = PkwLength::Three,
                        std::vector<std::uint16_t> pzd = {0x0237, 0x1000}) {
  return make_reply(address, Pkw{}, len, std::move(pzd));
}

inline Pkw read_request(std::uint16_t pnu) {
  Pkw p;
  p.id = request::kReadValue;
  p.pnu = pnu;
  p.pwe_count = 1;
  return p;
}

}  // namespace
}  // namespace liftd::uss
