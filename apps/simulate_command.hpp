// tdcr simulate: a scene's robot in motion under its timeline (tdcr/models/dynamics.hpp).
#pragma once

#include <string>
#include <vector>

namespace tdcr::cli {

/// @brief The usage lines of `tdcr simulate` (part of `tdcr --help`).
std::string simulate_usage();

/// @brief Runs `tdcr simulate ARGS...` (the arguments after "simulate"): writes one CSV row per
/// output step (-o FILE, else standard output). Returns the exit status: 0 every step converged,
/// 1 a step failed (the rows up to it are written; the message, with the time, residual and
/// iterations, goes to standard error). Throws InputError on bad arguments or scene (exit 2).
int run_simulate(const std::vector<std::string>& args);

}  // namespace tdcr::cli
