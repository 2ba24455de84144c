// `tdcr plot`: draws solved robots with the Python module (python -m tdcr.plot).
#pragma once

#include <string>
#include <vector>

namespace tdcr_cli {

/// Runs `python3 -m tdcr.plot ARGS` with PYTHONPATH pointing at tdcr's Python module (the installed
/// one beside this executable, else the build tree's) and returns its exit status; 3 with a message
/// if python3 cannot be started or tdcr was built without the module.
int run_plot(const std::vector<std::string>& args);

}  // namespace tdcr_cli
