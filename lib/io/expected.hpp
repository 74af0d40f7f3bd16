// A value or an error, for calls that must not throw (C++20 has no std::expected).
#pragma once

#include <type_traits>
#include <utility>
#include <variant>

namespace liftd::io {

/// Holds either a T (success) or an E (failure). Access the wrong side and the program aborts
/// (std::get on the wrong variant alternative); check ok() first.
template <class T, class E>
class [[nodiscard]] Expected {
 public:
  /// Success.
  Expected(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit
  /// Failure.
  Expected(E error) : v_(std::in_place_index<1>, std::move(error)) {}  // NOLINT: implicit

  /// True when a value is held.
  bool ok() const noexcept { return v_.index() == 0; }
  /// Same as ok().
  explicit operator bool() const noexcept { return ok(); }
  /// The value; only when ok().
  T& value() & { return std::get<0>(v_); }
  /// The value; only when ok().
  const T& value() const& { return std::get<0>(v_); }
  /// The value, moved out; only when ok().
  T&& value() && { return std::get<0>(std::move(v_)); }
  /// The error; only when !ok().
  const E& error() const& { return std::get<1>(v_); }

 private:
  std::variant<T, E> v_;
};

}  // namespace liftd::io
