// The command-line programs' option syntax, written once: "--name value" or "--name=value".
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tdcr/core/error.hpp"

namespace tdcr_cli {

/// Splits "--name=value" into name and value; a plain "--name" (or a positional argument) has no
/// inline value.
inline std::pair<std::string, std::optional<std::string>> split_option(const std::string& arg) {
  const auto eq = arg.find('=');
  if (arg.rfind("--", 0) != 0 || eq == std::string::npos) return {arg, std::nullopt};
  return {arg.substr(0, eq), arg.substr(eq + 1)};
}

/// The value of option `name` at args[i]: its inline value, else the next argument (i advances).
/// Throws tdcr::InputError naming the option if there is none.
inline std::string option_value(const std::vector<std::string>& args, std::size_t& i, const std::string& name,
                                const std::optional<std::string>& inline_value) {
  if (inline_value) return *inline_value;
  if (i + 1 >= args.size()) throw tdcr::InputError(name, "", "missing argument");
  return args[++i];
}

}  // namespace tdcr_cli
