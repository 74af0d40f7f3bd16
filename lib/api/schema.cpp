#include "api/schema.hpp"

#include <algorithm>
#include <utility>

namespace liftd::api {
namespace {

std::string quoted_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) {
    if (!out.empty()) out += ", ";
    out += '"' + name + '"';
  }
  return out;
}

bool fits(const ArgSpec& spec, const nlohmann::json& value) {
  switch (spec.type) {
    case ArgType::Bool:
      return value.is_boolean();
    case ArgType::Integer: {
      if (value.is_number_unsigned()) {
        const auto v = value.get<std::uint64_t>();
        if (v > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return false;
        const auto s = static_cast<std::int64_t>(v);
        return s >= spec.min && s <= spec.max;
      }
      if (value.is_number_integer()) {
        const auto v = value.get<std::int64_t>();
        return v >= spec.min && v <= spec.max;
      }
      return false;
    }
    case ArgType::String:
      if (!value.is_string()) return false;
      return spec.choices.empty() ||
             std::find(spec.choices.begin(), spec.choices.end(),
                       value.get_ref<const std::string&>()) != spec.choices.end();
    case ArgType::Any:
      return true;
  }
  return false;
}

/// An optional argument of `type` with no range or choices.
ArgSpec optional_arg(std::string name, ArgType type, std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = type;
  spec.description = std::move(description);
  return spec;
}

}  // namespace

ArgSpec flag_arg(std::string name, std::string description) {
  return optional_arg(std::move(name), ArgType::Bool, std::move(description));
}

ArgSpec text_arg(std::string name, std::string description) {
  return optional_arg(std::move(name), ArgType::String, std::move(description));
}

ArgSpec int_arg(std::string name, bool required, std::int64_t min, std::int64_t max,
                std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = ArgType::Integer;
  spec.required = required;
  spec.min = min;
  spec.max = max;
  spec.description = std::move(description);
  return spec;
}

ArgSpec choice_arg(std::string name, bool required, std::vector<std::string> choices,
                   std::string description) {
  ArgSpec spec;
  spec.name = std::move(name);
  spec.type = ArgType::String;
  spec.required = required;
  spec.choices = std::move(choices);
  spec.description = std::move(description);
  return spec;
}

std::string describe_allowed(const ArgSpec& spec) {
  switch (spec.type) {
    case ArgType::Bool:
      return "true or false";
    case ArgType::Integer: {
      const bool has_min = spec.min != std::numeric_limits<std::int64_t>::min();
      const bool has_max = spec.max != std::numeric_limits<std::int64_t>::max();
      if (has_min && has_max) {
        return "an integer " + std::to_string(spec.min) + ".." + std::to_string(spec.max);
      }
      if (has_min) return "an integer >= " + std::to_string(spec.min);
      if (has_max) return "an integer <= " + std::to_string(spec.max);
      return "an integer";
    }
    case ArgType::String:
      return spec.choices.empty() ? "a string" : "one of " + quoted_list(spec.choices);
    case ArgType::Any:
      return "any JSON value";
  }
  return "any JSON value";
}

std::optional<Error> validate_args(const nlohmann::json& request, const ArgSchema& schema) {
  for (const auto& [key, value] : request.items()) {
    if (key == "cmd" || key == "id") continue;
    const auto spec = std::find_if(schema.begin(), schema.end(),
                                   [&key = key](const ArgSpec& s) { return s.name == key; });
    if (spec == schema.end()) {
      std::vector<std::string> names;
      for (const auto& s : schema) names.push_back(s.name);
      std::string allowed = names.empty() ? "this command takes no arguments"
                                          : "allowed fields: " + quoted_list(names);
      return Error{ErrorCode::BadRequest, "unknown field \"" + capped(key) + "\" (" + allowed + ")",
                   capped(key)};
    }
    if (!fits(*spec, value)) {
      return Error{ErrorCode::BadRequest,
                   "field \"" + key + "\" must be " + describe_allowed(*spec), key};
    }
  }
  for (const auto& spec : schema) {
    if (spec.required && !request.contains(spec.name)) {
      return Error{ErrorCode::BadRequest,
                   "missing field \"" + spec.name + "\" (" + describe_allowed(spec) + ")",
                   spec.name};
    }
  }
  return std::nullopt;
}

}  // namespace liftd::api
