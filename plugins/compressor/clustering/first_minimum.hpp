// The index of the first smallest of `count` floats, 16 lanes at a time.
// A compare-and-select argmin over a row of cluster distances does not
// vectorise (it carries the index), and it ran about as long as the GEMM
// that made the row. Here the minimum is a lane-wise min, then the first
// index holding it is found by a compare pass. Same answer as a scalar
// scan with `<` for finite values: the first occurrence of the minimum.
#pragma once
#include <cstring>
#include <limits>

namespace prt::clustering {

inline int first_minimum(const float* values, int count) {
  typedef float Lanes __attribute__((vector_size(64)));
  constexpr int kLanes = 16;
  const float inf = std::numeric_limits<float>::infinity();
  float smallest = inf;
  int j = 0;
  if (count >= kLanes) {
    Lanes low;
    std::memcpy(&low, values, sizeof low);
    for (j = kLanes; j + kLanes <= count; j += kLanes) {
      Lanes v;
      std::memcpy(&v, values + j, sizeof v);
      low = (v < low) | (low != low) ? v : low;  // a NaN lane takes the next value
    }
    for (int lane = 0; lane < kLanes; ++lane)
      smallest = low[lane] < smallest ? low[lane] : smallest;
  }
  for (; j < count; ++j) smallest = values[j] < smallest ? values[j] : smallest;
  if (!(smallest < inf)) return 0;  // all NaN or infinite: the first, as a scalar scan keeps
  for (int i = 0; i < count; ++i)
    if (values[i] == smallest) return i;
  return 0;
}

}  // namespace prt::clustering
