// The one clock every timing in the library and its tools reads.
#pragma once

#include <chrono>

namespace rtcd {

using Clock = std::chrono::steady_clock;

inline double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}
inline double seconds_since(Clock::time_point t) { return seconds_between(t, Clock::now()); }

}  // namespace rtcd
