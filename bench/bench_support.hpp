#pragma once
//! What the benchmark programs share: clocks that tell CPU from waiting on a shared machine.
#include <sys/resource.h>

#include <chrono>

namespace topotrack::bench {

//! CPU seconds of all threads of the process so far: on a shared machine wall time also counts waiting.
inline double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

//! Wall-clock milliseconds since t0.
inline double milliseconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace topotrack::bench
