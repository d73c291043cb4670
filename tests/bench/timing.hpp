// Timing helpers shared by the benchmarks: medians, never single runs (the
// machines are shared and noisy).
#pragma once
#include <algorithm>
#include <functional>
#include <utility>
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

// Median wall times of run_a() and run_b(), in seconds, over `repeats` calls
// of each, the calls alternating, so that the machine's drift (up to 2x over
// minutes) hits a stage and its bound alike.
template <class RunA, class RunB>
std::pair<double, double> alternating_median_seconds(int repeats, const RunA& run_a,
                                                     const RunB& run_b) {
  std::vector<double> a, b;
  for (int r = 0; r < repeats; ++r) {
    Stopwatch clock_a;
    run_a();
    a.push_back(clock_a.seconds());
    Stopwatch clock_b;
    run_b();
    b.push_back(clock_b.seconds());
  }
  return {median(a), median(b)};
}

// The same for any number of runs, taken in turn: medians in run order.
inline std::vector<double> alternating_medians(int repeats,
                                               const std::vector<std::function<void()>>& runs) {
  std::vector<std::vector<double>> times(runs.size());
  for (int r = 0; r < repeats; ++r)
    for (std::size_t i = 0; i < runs.size(); ++i) {
      Stopwatch clock;
      runs[i]();
      times[i].push_back(clock.seconds());
    }
  std::vector<double> medians;
  for (auto& t : times) medians.push_back(median(t));
  return medians;
}

}  // namespace prt::bench
