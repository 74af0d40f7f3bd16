// Fuzzes the config loader: any bytes must give a config or problems, never a crash or an
// escaping exception.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config/config.hpp"
#include "kinds/config_schema.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto result = liftd::kinds::parse_config(text, "fuzz");
  if (result.ok()) {
    (void)liftd::config::to_json(result.config, liftd::kinds::config_schema()).dump();
  }
  for (const auto& problem : result.problems) (void)liftd::config::to_string(problem);
  return 0;
}
