// Argument schemas of API commands: one table entry per field, validated generically.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/result.hpp"

namespace liftd::api {

/// JSON type an argument must have.
enum class ArgType : std::uint8_t {
  Bool,     ///< true or false
  Integer,  ///< a JSON number without fraction or exponent, within [min, max]
  String,   ///< a string, one of `choices` when that is not empty
  Any,      ///< any JSON value
};

/// One argument of a command.
struct ArgSpec {
  std::string name;                                             ///< field name in the request
  ArgType type = ArgType::Any;                                  ///< required JSON type
  bool required = false;                                        ///< must be present
  std::int64_t min = std::numeric_limits<std::int64_t>::min();  ///< Integer: lowest allowed
  std::int64_t max = std::numeric_limits<std::int64_t>::max();  ///< Integer: highest allowed
  std::vector<std::string> choices;                             ///< String: allowed values
  std::string description;                                      ///< one line, for help and docs
};

/// The arguments of one command (fields other than "cmd" and "id").
using ArgSchema = std::vector<ArgSpec>;

/// An optional boolean argument.
ArgSpec flag_arg(std::string name, std::string description);
/// An integer argument within [min, max].
ArgSpec int_arg(std::string name, bool required, std::int64_t min, std::int64_t max,
                std::string description);
/// An optional free-text string argument (the command checks its form and says what is allowed).
ArgSpec text_arg(std::string name, std::string description);
/// A string argument that must be one of `choices`.
ArgSpec choice_arg(std::string name, bool required, std::vector<std::string> choices,
                   std::string description);

/// The value of the (validated) argument `name` of `request`, or `fallback` when it is absent.
template <typename T>
T arg_or(const nlohmann::json& request, const char* name, T fallback) {
  const auto it = request.find(name);
  return it == request.end() ? fallback : it->get<T>();
}

/// The wire names of an enum as the choices of a choice_arg.
template <std::size_t N>
std::vector<std::string> names_of(const std::array<std::string_view, N>& names) {
  return {names.begin(), names.end()};
}

/// The enum value named `name` in `names` (its wire names in enum order); `name` was validated
/// against names_of(names).
template <typename Enum, std::size_t N>
Enum enum_of(const std::array<std::string_view, N>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return static_cast<Enum>(it - names.begin());
}

/// What a value for `spec` must look like, e.g. "an integer 0..999" or "one of \"mains\",
/// \"emergency\"".
std::string describe_allowed(const ArgSpec& spec);

/// Checks a request object against a schema: every field other than "cmd" and "id" must be in
/// the schema with the right type and range, and every required field present. Returns the first
/// violation as a bad_request error naming the field, or nullopt.
std::optional<Error> validate_args(const nlohmann::json& request, const ArgSchema& schema);

}  // namespace liftd::api
