// libFuzzer target: request lines with duplicate keys and raw NULs through the dispatcher. The
// oracle: a line with a raw NUL, or valid JSON with a key twice in one object, is answered with
// bad_json and runs nothing; every error message quotes at most 64 bytes of input.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"
#include "api/handler_fuzz.hpp"

namespace {

// The first input byte says where to plant what: bit 0 a NUL, bit 1 a repeated "cmd" key.
std::string shape(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return {};
  std::string line(reinterpret_cast<const char*>(data + 1), size - 1);
  const std::uint8_t mode = data[0];
  if ((mode & 2) != 0) line = R"({"cmd":"drive_reset","cmd":)" + line;
  if ((mode & 1) != 0) line.insert(line.size() / 2, 1, '\0');
  return line;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static liftd::api::testing::FakeBackend backend;
  static const liftd::api::Dispatcher dispatcher =
      liftd::api::testing::every_command_dispatcher(backend);
  static liftd::api::testing::FuzzSession session;
  liftd::api::Peer peer;
  peer.access = {true, true, true};
  const std::string line = shape(data, size);
  const bool has_nul = line.find('\0') != std::string::npos;
  const bool duplicate = !has_nul && liftd::api::find_duplicate_key(line).has_value();
  const auto document = nlohmann::json::parse(line, nullptr, false);
  const bool valid_json = !has_nul && !document.is_discarded();
  int replies = 0;
  dispatcher.handle_line(line, peer, session, [&](std::string reply, bool ok) {
    ++replies;
    const auto parsed = nlohmann::json::parse(reply, nullptr, false);
    if (parsed.is_discarded() || parsed.at("ok") != ok) std::abort();
    if ((has_nul || (valid_json && duplicate)) &&
        (ok || parsed.at("error").at("code") != "bad_json")) {
      std::abort();
    }
    // 64 bytes of echoed input plus the longest fixed text around it.
    if (!ok && parsed.at("error").at("message").get<std::string>().size() > 64 + 400) {
      std::abort();
    }
  });
  if (replies != 1) std::abort();
  if ((has_nul || (valid_json && duplicate)) && !backend.requests_seen.empty()) std::abort();
  backend.requests_seen.clear();
  return 0;
}
