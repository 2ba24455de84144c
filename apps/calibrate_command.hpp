// tdcr calibrate: fit a model's parameters to measured shapes (tdcr/models/calibration.hpp).
#pragma once

#include <string>
#include <vector>

namespace tdcr::cli {

/// @brief The usage lines of `tdcr calibrate` (part of `tdcr --help`).
std::string calibrate_usage();

/// @brief Runs `tdcr calibrate ARGS...` (the arguments after "calibrate"). Prints the report;
/// writes the calibrated scene with -o. Returns the exit status: 0 converged, 1 not converged
/// (the report is still printed). Throws InputError on bad arguments, scene or data (exit 2).
int run_calibrate(const std::vector<std::string>& args);

}  // namespace tdcr::cli
