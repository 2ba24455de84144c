// Running the `tdcr` program from a test as a user runs it: its exit status and both streams.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace tdcr_test {

/// What one run of the program printed, and how it ended.
struct CliRun {
  int status = -1;  ///< Exit status, or -1 if the program did not exit normally (crash, signal).
  std::string out;
  std::string err;
};

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// `s` quoted for the shell.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// Runs `binary args` (arguments already quoted as needed) through the shell; standard error
/// goes through `err_file`.
inline CliRun run_program(const std::string& binary, const std::string& args, const std::filesystem::path& err_file) {
  const std::string cmd = quote(binary) + " " + args + " 2>" + quote(err_file.string());
  CliRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
  const int st = ::pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.err = read_file(err_file);
  return r;
}

}  // namespace tdcr_test
