// The commands run by the Python module: `tdcr plot` (python -m tdcr.plot) draws solved robots,
// `tdcr view` (python -m tdcr.view) serves the interactive viewer.
#pragma once

#include <string>
#include <vector>

namespace tdcr_cli {

/// Runs `python3 -m tdcr.plot ARGS` with PYTHONPATH pointing at tdcr's Python module (the installed
/// one beside this executable, else the build tree's) and returns its exit status; 3 with a message
/// if python3 cannot be started or tdcr was built without the module.
int run_plot(const std::vector<std::string>& args);

/// The same for `python3 -m tdcr.view ARGS` (the viewer's server; runs until interrupted).
int run_view(const std::vector<std::string>& args);

}  // namespace tdcr_cli
