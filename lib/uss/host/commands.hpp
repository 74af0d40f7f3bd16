// The API commands only the USS lift offers: a PKW request to a slave's parameters (uss_read,
// uss_write) and a mirror telegram (uss_mirror). The dispatcher knows them on every lift and
// answers them `not_offered` on a drive kind without the capability (CommandSpec::needs).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "api/result.hpp"
#include "drive/drive.hpp"

namespace liftd::daemon {

/// What a parameter request addresses (USS C 4.2.2: IND selects an array element, a
/// description element or a text element).
enum class ParameterTarget : std::uint8_t { Value, Array, Description, Text };
/// Wire names of ParameterTarget, in enum order.
inline constexpr std::array<std::string_view, 4> kParameterTargets = {"value", "array",
                                                                      "description", "text"};

/// Arguments of `uss_read` and `uss_write` (USS C 4: one PKW request to one slave).
struct ParameterArgs {
  std::optional<int> address;  ///< USS slave 0..31; nullopt: the drive (uss.drive_address)
  int pnu = 0;                 ///< parameter number 0..2047 (PKE bits 0..10)
  ParameterTarget target = ParameterTarget::Value;
  int index = 0;           ///< element of an array, description or text, passed unchanged (IND)
  bool write = false;      ///< uss_write
  std::int64_t value = 0;  ///< uss_write: the value
  bool dword = false;      ///< uss_write: a double word (else a word)
  bool eeprom = false;     ///< uss_write: also into the drive's EEPROM
};

/// What the USS lift's backend serves besides api::Backend: the parameter commands. Called on
/// the io_context's thread; every Responder must be called exactly once on that thread.
class UssCommandBackend {
 public:
  virtual ~UssCommandBackend() = default;
  /// One PKW request (USS C 4); the result is the slave's answer.
  virtual void parameter(const ParameterArgs& args, api::Responder done) = 0;
  /// A mirror telegram to `address` (nullopt: the drive) as a link test (USS A 5.3).
  virtual void mirror(std::optional<int> address, api::Responder done) = 0;
};

}  // namespace liftd::daemon
