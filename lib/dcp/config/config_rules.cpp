#include "dcp/registry_entry.hpp"

#include <algorithm>
#include <array>
#include <sstream>
#include <utility>

#include "config/schema.hpp"
#include "dcp/charset.hpp"
#include "dcp/config/section.hpp"

namespace liftd::dcp {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, 5> kDataInfoTypeNames{"0", "1", "2", "3", "4"};
// DCP 5.12.9: I9 carries the position as a sign and six decimal digits of mm.
constexpr std::int64_t kMaxLevelMm = 999999;

std::string two_capitals_rule(const std::string& text) {
  if (text.size() != 2 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= 'A' && c <= 'Z'; })) {
    return "must be exactly two capital letters A-Z";
  }
  return {};
}

// DCP 5.12.2.3: the codes the spec's table gives to named companies, lift-controller and drive
// makers alike. Sending one of them in I0 claims to be that company's controller.
std::string maker_code_rule(const std::string& text) {
  if (auto error = two_capitals_rule(text); !error.empty()) return error;
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 21> kTaken = {{
      {"BP", "Boehnke + Partner"},
      {"KN", "Kollmorgen"},
      {"NL", "NEW LIFT"},
      {"OS", "OSMA-Aufzuege"},
      {"LI", "Schneider Steuerungstechnik"},
      {"ST", "Strack Lift Automation"},
      {"AB", "ABB"},
      {"BF", "Brunner & Fecher"},
      {"BH", "Bucher Hydraulics"},
      {"CT", "Control Techniques"},
      {"DA", "Danfoss"},
      {"DE", "Emotron"},
      {"FE", "Fuji Electric"},
      {"SS", "Gefran"},
      {"KW", "KW-Aufzugstechnik"},
      {"MT", "MagneTek"},
      {"RS", "RST Elektronik"},
      {"TY", "Thyssen Krupp"},
      {"VZ", "Venzke-DriveCon"},
      {"YE", "Yaskawa"},
      {"ZA", "Ziehl-Abegg"},
  }};
  for (const auto& [code, owner] : kTaken) {
    if (text == code) {
      return "is " + std::string(owner) +
             "'s code in the DCP 5.12.2.3 table; use a code that table does not list (liftd's "
             "default is LD)";
    }
  }
  return {};
}

// A floor name as the display shows it: its appendix A bytes, nullopt where it has a character
// the display lacks. None of those characters has a canonical decomposition or is a combining
// mark, so every displayable name is already in Unicode NFC: two names that are equal after
// normalisation are equal byte for byte, and no normalisation table is needed.
std::optional<std::string> display_bytes(std::string_view name) {
  std::array<std::uint8_t, 64> out{};
  const CharsetResult r = from_utf8(name, out);
  if (!r.ok()) return std::nullopt;
  return std::string(reinterpret_cast<const char*>(out.data()), r.written);
}

std::string dcp_summary(const config::Config& cfg) {
  std::ostringstream out;
  out << "drive:    " << drive::to_string(cfg.drive.kind) << " on " << cfg.drive.device
      << " (rs485 " << config::to_string(cfg.drive.rs485) << ")\n";
  out << "dcp:      maker " << dcp_section(cfg).manufacturer << ", language "
      << dcp_section(cfg).language << ", data-information-type " << dcp_section(cfg).data_info_type
      << ", link fault after " << dcp_section(cfg).link_fault_frames << " frames\n";
  return out.str();
}

std::vector<config::Key> dcp_keys() {
  using config::Config;
  using config::DcpConfig;
  std::vector<config::Key> t;
  t.push_back(config::string_key(
      "dcp.manufacturer", 2, 2, "two capital letters A-Z, not a code of the DCP 5.12.2.3 table",
      maker_code_rule, "lift-controller maker code sent in I0 (DCP 5.12.2.3)",
      config::kind_section<config::DcpConfig>, &DcpConfig::manufacturer));
  t.push_back(config::string_key("dcp.language", 2, 2, "two capital letters A-Z (ISO 639)",
                                 two_capitals_rule,
                                 "language code sent in I0; the drive falls back to English "
                                 "(DCP 5.12.2)",
                                 config::kind_section<config::DcpConfig>, &DcpConfig::language));
  config::Key k;
  k.path = "dcp.data_info_type";
  k.type = config::Type::choice;
  for (auto name : kDataInfoTypeNames) k.choices.emplace_back(name);
  k.description =
      "data-information-type set with I1: what the drive's data bytes carry (DCP 5.12.3)";
  k.set = [](Config& c, const json& v) { dcp_section(c).data_info_type = v.get<std::string>()[0]; };
  k.get = [](const Config& c) { return json(std::string(1, dcp_section(c).data_info_type)); };
  t.push_back(std::move(k));
  t.push_back(config::bool_key("dcp.extended_position",
                               "ask for the extended I9 reply with the measured travel distance "
                               "(DCP 5.12.9)",
                               config::kind_section<config::DcpConfig>,
                               &DcpConfig::extended_position));
  t.push_back(
      config::int_key("dcp.link_fault_frames", 1, 100,
                      "consecutive bad or missing replies that make a link fault (DCP 7.3: 10)",
                      config::kind_section<config::DcpConfig>, &DcpConfig::link_fault_frames));
  t.push_back(config::int_key("dcp.link_recover_frames", 1, 100,
                              "consecutive good replies that end a link fault (DCP 7.3: 10)",
                              config::kind_section<config::DcpConfig>,
                              &DcpConfig::link_recover_frames));
  t.push_back(config::int_key("dcp.request_timeout_ms", 100, 10000,
                              "how long to wait for the drive's reply to an I-message",
                              config::kind_section<config::DcpConfig>,
                              &DcpConfig::request_timeout_ms));
  return t;
}

}  // namespace

config::KindRules RegistryEntry::config_rules() {
  config::KindRules rules;
  rules.kind = drive::Kind::Dcp;
  rules.keys = dcp_keys();
  rules.summary = dcp_summary;
  return rules;
}

config::FloorRules RegistryEntry::floor_rules() {
  config::FloorRules rules;
  rules.charset_name = "the DCP display character set";
  rules.charset_details =
      "DCP appendix A: ASCII letters, digits, space and signs except \\ ~, and \u00e4 \u00f6 "
      "\u00fc \u00c4 \u00d6 \u00dc \u00df \u00b0 \u00b1 \u00b5 and some Greek letters and arrows";
  rules.shown_as = display_bytes;
  rules.max_level_mm = kMaxLevelMm;
  return rules;
}

}  // namespace liftd::dcp
