// What `rtcd run` and `rtcd bench` show and write about where they ran: a
// progress display and the machine's description.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "rtcd/clock.hpp"

namespace rtcd::app {

inline std::string machine() {
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpu, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

// A bar with rate and time left on a terminal; otherwise a plain line at the
// end and at each tenth at most every 5 s.
class Progress {
 public:
  explicit Progress(uint64_t total, std::string label = "", std::string unit = "steps")
      : total_(total), label_(std::move(label)), unit_(std::move(unit)), tty_(isatty(STDOUT_FILENO)),
        start_(Clock::now()) {}
  void update(uint64_t done) {
    if (total_ == 0) return;
    const double elapsed = seconds_since(start_);
    const double rate = elapsed > 0 ? double(done) / elapsed : 0;
    const double left = rate > 0 ? double(total_ - done) / rate : 0;
    const char* label = label_.c_str();
    const char* gap = label_.empty() ? "" : "  ";
    if (tty_) {
      const int width = 30, filled = int(width * done / total_);
      std::printf("\r%s%s[%s%s] %3d%%  %llu/%llu %s  %.1f %s/s  %.0f s left ", label, gap,
                  std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(), int(100 * done / total_),
                  (unsigned long long)done, (unsigned long long)total_, unit_.c_str(), rate, unit_.c_str(), left);
      if (done == total_) std::printf("\n");
      std::fflush(stdout);
    } else if (done == total_ || (10 * done / total_ != 10 * (done - 1) / total_ && elapsed - printed_ > 5)) {
      printed_ = elapsed;
      std::printf("%s%s%s %llu/%llu  %.1f %s/s  %.0f s left\n", label, gap, unit_.c_str(), (unsigned long long)done,
                  (unsigned long long)total_, rate, unit_.c_str(), left);
      std::fflush(stdout);
    }
  }

 private:
  uint64_t total_;
  std::string label_, unit_;
  bool tty_;
  double printed_ = -1e9;  // when the last plain line was printed
  Clock::time_point start_;
};

}  // namespace rtcd::app
