// Timing helpers shared by the benchmarks: medians, never single runs (the
// machines are shared and noisy).
#pragma once
#include <algorithm>
#include <vector>

#include "prt/progress.hpp"

namespace prt::bench {

inline double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// Median wall time of `repeats` calls of run(), in seconds.
template <class Run>
double median_seconds(int repeats, const Run& run) {
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    Stopwatch clock;
    run();
    times.push_back(clock.seconds());
  }
  return median(times);
}

}  // namespace prt::bench
