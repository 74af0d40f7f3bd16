// The Schema and the helpers every section's rules use.
#include "config/schema.hpp"

#include <algorithm>
#include <cstdio>

namespace liftd::config {
namespace {

using nlohmann::json;

// The closest candidate within a small edit distance, for "did you mean".
std::optional<std::string> closest(std::string_view word, const std::vector<std::string>& pool) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& candidate : pool) {
    // The distance is at least the difference in length: a candidate that cannot beat the best
    // so far is not measured (a long unknown word against every key costs otherwise).
    const std::size_t length_gap = word.size() > candidate.size() ? word.size() - candidate.size()
                                                                  : candidate.size() - word.size();
    std::size_t d = length_gap < best_distance ? edit_distance(word, candidate) : length_gap;
    // A word that is a longer or shorter form of a candidate ("warning", "warn") is close too.
    const std::string_view shorter = word.size() < candidate.size() ? word : candidate;
    const std::string_view longer = word.size() < candidate.size() ? candidate : word;
    constexpr std::size_t kMinPrefix = 3;
    if (shorter.size() >= kMinPrefix && longer.substr(0, shorter.size()) == shorter) {
      d = std::min<std::size_t>(d, 2);
    }
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

// The byte offset of the first control character (C0, DEL, or a UTF-8 encoded C1 U+0080..U+009F),
// or npos. A NUL would cut a path short where the kernel reads it; the others hide in logs.
std::size_t find_control(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x20U || byte == 0x7FU) return i;
    if (byte == 0xC2U && i + 1 < text.size()) {
      const auto next = static_cast<unsigned char>(text[i + 1]);
      if (next >= 0x80U && next <= 0x9FU) return i;
    }
  }
  return std::string_view::npos;
}

}  // namespace

void Schema::add(std::vector<Key> keys) {
  for (auto& key : keys) keys_.push_back(std::move(key));
}

void Schema::add(KindRules kind) {
  keys_.insert(keys_.end(), kind.keys.begin(), kind.keys.end());
  kinds_.push_back(std::move(kind));
}

const KindRules* Schema::rules_of(DriveKind kind) const noexcept {
  for (const auto& rules : kinds_) {
    if (rules.kind == kind) return &rules;
  }
  return nullptr;
}

std::string json_quoted(std::string_view text) {
  return json(std::string(text)).dump();
}

std::string show(const json& value) {
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  constexpr std::size_t kMaxShown = 60;
  if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
  return text;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& pool) {
  auto best = closest(word, pool);
  return best ? " (did you mean " + json_quoted(*best) + "?)" : std::string{};
}

bool is_integer(const json& value) {
  return value.is_number_integer() || value.is_number_unsigned();
}

bool check_integer(const json& value, const std::string& where, std::int64_t min, std::int64_t max,
                   Problems& problems) {
  const std::string range = std::to_string(min) + ".." + std::to_string(max);
  if (!is_integer(value)) {
    problems.push_back({where, "expected an integer " + range + ", got " + show(value)});
    return false;
  }
  const bool negative = !value.is_number_unsigned() && value.get<std::int64_t>() < 0;
  if (!negative && value.get<std::uint64_t>() > static_cast<std::uint64_t>(max)) {
    problems.push_back({where, show(value) + " is out of range: allowed " + range});
    return false;
  }
  if (value.get<std::int64_t>() < min) {
    problems.push_back({where, show(value) + " is out of range: allowed " + range});
    return false;
  }
  return true;
}

const json* find_value(const json& document, const std::string& path) {
  const json* node = &document;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    const std::string part = path.substr(start, dot == std::string::npos ? dot : dot - start);
    if (!node->is_object()) return nullptr;
    const auto it = node->find(part);
    if (it == node->end()) return nullptr;
    node = &*it;
    if (dot == std::string::npos) return node;
    start = dot + 1;
  }
}

std::string control_rule(const std::string& text) {
  const std::size_t at = find_control(text);
  if (at == std::string::npos) return {};
  char code[8];
  std::snprintf(code, sizeof code, "0x%02X",
                static_cast<unsigned>(static_cast<unsigned char>(text[at])));
  return std::string("contains a control character (byte ") + code + " at offset " +
         std::to_string(at) + "): not allowed";
}

std::string absolute_path_rule(const std::string& text) {
  if (text.empty() || text.front() != '/') return "must be an absolute path (start with /)";
  return control_rule(text);
}

Key custom_key(std::string path, std::string type_text, std::string allowed_text,
               std::string description,
               std::function<void(const json&, const std::string&, Config&, Problems&)> custom,
               std::function<json(const Config&)> get) {
  Key key;
  key.path = std::move(path);
  key.type = Type::custom;
  key.type_text = std::move(type_text);
  key.allowed_text = std::move(allowed_text);
  key.description = std::move(description);
  key.custom = std::move(custom);
  key.get = std::move(get);
  return key;
}

}  // namespace liftd::config
