// A drive kind's configuration section as an empty file gives it: every key of `<kind>.*` has
// the documented default (docs/config.md), and the table a kind's test gives names every key of
// its section (tests/<kind>/host/defaults_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "kinds/config_schema.hpp"

namespace liftd::testing {

/// Key path ("/sch001/base") -> its documented default.
using SectionDefaults = std::vector<std::pair<std::string, nlohmann::json>>;

inline void expect_section_defaults(const std::string& kind, const SectionDefaults& expected) {
  const config::LoadResult result = kinds::parse_config("{}", "test");
  ASSERT_TRUE(result.ok());
  const nlohmann::json dumped = config::to_json(result.config, kinds::config_schema());
  for (const auto& [pointer, value] : expected) {
    EXPECT_EQ(dumped.at(nlohmann::json::json_pointer(pointer)), value) << pointer;
  }
  std::size_t keys = 0;
  for (const auto& path : config::key_paths(kinds::config_schema())) {
    keys += path.rfind(kind + ".", 0) == 0 ? 1U : 0U;
  }
  EXPECT_EQ(keys, expected.size()) << "a key of " << kind << ".* missing from the table";
}

}  // namespace liftd::testing
