// Runs the `rtcd` command as a user would, for the suites that test it end
// to end.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace rtcd::test {

struct Outcome {
  int code;  // the exit code; -1 when killed by a signal
  std::string out;
};

// Runs `prefix rtcd args` through the shell, stderr folded into the output.
inline Outcome run_command(const std::string& args, const std::string& prefix = "") {
  const std::string cmd = prefix + std::string(RTCD_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace rtcd::test
