#pragma once
/// What every backend's Options struct shares: the result of validate(), and choices as
/// `enum class` with one table of names each (to_string / from_string), parsed once at the
/// boundary (scene files, the command line) so that no step() compares strings.
#include <array>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace hooke {

/// The result of an Options struct's validate(): valid (message empty), or the first field that
/// breaks a rule. `field` is the field's name (as in the struct; scene readers map it to their key)
/// and `message` says "FIELD = VALUE: rule", so it reads on its own.
struct OptionError {
  std::string field;
  std::string message;
  /// True when the options are valid.
  bool ok() const { return message.empty(); }
};

/// The OptionError of a field that breaks its rule: message "FIELD = VALUE: rule".
template <class T>
OptionError option_error(const std::string& field, const T& value, const std::string& rule) {
  std::ostringstream os;
  os << field << " = " << value << ": " << rule;
  return {field, os.str()};
}

/// Names of the values of an enum class E, in the enum's order (E's values must be 0, 1, ...).
/// Specialise it next to E:
///   template <> struct EnumNames<Acceleration> {
///     static constexpr std::array<const char*, 3> names = {"none", "chebyshev", "lbfgs"};
///   };
template <class E>
struct EnumNames;

/// The name of a choice, as written in scene files ("chebyshev").
template <class E, class = decltype(EnumNames<E>::names)>
const char* to_string(E e) {
  const auto i = static_cast<size_t>(e);
  return i < EnumNames<E>::names.size() ? EnumNames<E>::names[i] : "unknown";
}

/// The choice called `name`, or nothing if no value of E has that name.
template <class E>
std::optional<E> from_string(std::string_view name) {
  const auto& names = EnumNames<E>::names;
  for (size_t i = 0; i < names.size(); ++i)
    if (name == names[i]) return static_cast<E>(i);
  return std::nullopt;
}

/// "a, b, c": every name of E, for messages and --help.
template <class E>
std::string choice_names() {
  std::string s;
  for (const char* n : EnumNames<E>::names) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

}  // namespace hooke
