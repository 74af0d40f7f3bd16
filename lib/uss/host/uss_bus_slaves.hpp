// The USS bus's slaves from the configuration: shared by the master's and the simulator's setup.
#pragma once

#include <vector>

#include "config/config.hpp"
#include "uss/config/section.hpp"
#include "uss/pkw.hpp"

namespace liftd::daemon {

inline uss::PkwLength pkw_length_of(config::UssPkw pkw) {
  switch (pkw) {
    case config::UssPkw::none:
      return uss::PkwLength::None;
    case config::UssPkw::three:
      return uss::PkwLength::Three;
    case config::UssPkw::four:
      return uss::PkwLength::Four;
    case config::UssPkw::variable:
      return uss::PkwLength::Variable;
  }
  return uss::PkwLength::Four;
}

/// Every slave on the bus, the drive first.
inline std::vector<config::UssSlave> bus_slaves(const config::Config& c) {
  std::vector<config::UssSlave> out;
  out.push_back(
      {uss_section(c).drive_address, uss_section(c).drive_pkw, uss_section(c).drive_pzd_words});
  for (const auto& s : uss_section(c).slaves) out.push_back(s);
  return out;
}

}  // namespace liftd::daemon
