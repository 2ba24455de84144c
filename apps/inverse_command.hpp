// tdcr inverse: tensions that put the tip at a target (tdcr/models/inverse_solve.hpp).
#pragma once

#include <string>
#include <vector>

namespace tdcr::cli {

/// @brief The usage lines of `tdcr inverse` (part of `tdcr --help`).
std::string inverse_usage();

/// @brief Runs `tdcr inverse ARGS...` (the arguments after "inverse"). Prints the result; returns
/// the exit status: 0 converged, 1 target not reached (the closest pose is printed). Throws
/// InputError on bad arguments or a bad scene (exit 2 in main).
int run_inverse(const std::vector<std::string>& args);

}  // namespace tdcr::cli
