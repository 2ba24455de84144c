/// @file error.hpp
/// @brief The exception thrown for bad input: it names the field (a JSON-style path such as
/// `robot.segments[1].length`) and the offending value.
#pragma once

#include <stdexcept>
#include <string>

namespace tdcr {

/// @brief Invalid input to tdcr: a scene, robot, option or file that cannot be used.
///
/// Every validation in tdcr (scene files and the C++ API alike) throws this type, so callers can
/// report `field()` and `value()` to a user. `what()` is the full message:
/// "<field>: <reason> (got <value>)".
class InputError : public std::runtime_error {
 public:
  /// @brief An error about `field` holding `value`.
  /// @param field Path of the offending field (JSON-style, e.g. `robot.segments[1].length`; a
  ///   file name for unreadable or malformed files; a command-line option such as
  ///   `--integrator`).
  /// @param value The offending value as text; empty when the field is missing or the value
  ///   does not apply (then "(got ...)" is left out of the message).
  /// @param reason What is wrong, e.g. "must be positive".
  InputError(std::string field, std::string value, const std::string& reason)
      : std::runtime_error(field + ": " + reason + (value.empty() ? "" : " (got " + value + ")")),
        field_(std::move(field)),
        value_(std::move(value)) {}
  /// @brief Path of the offending field, e.g. `robot.segments[0].tendons[2].x`.
  const std::string& field() const { return field_; }
  /// @brief The offending value as text (may be empty when the field is missing).
  const std::string& value() const { return value_; }

 private:
  std::string field_;
  std::string value_;
};

/// @brief Format a double for an error message (shortest round-trip, "nan", "inf").
std::string format_value(double v);

}  // namespace tdcr
