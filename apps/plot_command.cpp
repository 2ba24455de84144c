#include "plot_command.hpp"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace tdcr_cli {
namespace {

constexpr int kExitInternal = 3;

#ifdef TDCR_PYTHON_BUILD_DIR
bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

/// Directory of the running executable ("" if unknown).
std::string exe_dir() {
  std::vector<char> buf(4096);
  const ssize_t n = ::readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  if (n <= 0) return "";
  std::string path(buf.data(), static_cast<std::size_t>(n));
  return path.substr(0, path.find_last_of('/'));
}

/// The directory holding the package tdcr: the installed one (relative to bin/) first, so an
/// installed tdcr uses its installed module, else the build tree's.
std::string module_dir() {
  const std::string installed = exe_dir() + "/" TDCR_PYTHON_INSTALL_DIR;
  if (exists(installed + "/tdcr/__init__.py")) return installed;
  return TDCR_PYTHON_BUILD_DIR;
}
#endif

}  // namespace

int run_python_command(const char* command, const char* module, const std::vector<std::string>& args) {
#ifndef TDCR_PYTHON_BUILD_DIR
  (void)args;
  (void)module;
  std::fprintf(stderr, "error: tdcr %s needs the Python module, and this tdcr was built without it "
                       "(configure with -DTDCR_BUILD_PYTHON=ON and pybind11 installed)\n", command);
  return kExitInternal;
#else
  const std::string python = exists(TDCR_PYTHON_EXECUTABLE) ? TDCR_PYTHON_EXECUTABLE : "python3";
  std::string pythonpath = module_dir();
  if (const char* old = std::getenv("PYTHONPATH"); old && *old) pythonpath += std::string(":") + old;

  std::vector<std::string> argv_s = {python, "-m", module};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);

  std::fflush(stdout);
  const pid_t pid = ::fork();
  if (pid < 0) {
    std::fprintf(stderr, "internal error: cannot start %s: %s\n", python.c_str(), std::strerror(errno));
    return kExitInternal;
  }
  if (pid == 0) {
    ::setenv("PYTHONPATH", pythonpath.c_str(), 1);
    ::execvp(argv[0], argv.data());
    std::fprintf(stderr, "error: tdcr %s needs python3 with numpy (and matplotlib for plots); cannot run '%s': %s\n",
                 command, python.c_str(), std::strerror(errno));
    std::_Exit(kExitInternal);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return kExitInternal;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  std::fprintf(stderr, "internal error: %s was killed by signal %d\n", python.c_str(), WTERMSIG(status));
  return kExitInternal;
#endif
}

int run_plot(const std::vector<std::string>& args) { return run_python_command("plot", "tdcr.plot", args); }

int run_view(const std::vector<std::string>& args) { return run_python_command("view", "tdcr.view", args); }

}  // namespace tdcr_cli
