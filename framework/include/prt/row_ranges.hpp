// Ranges of rows (a signal's rows are the mesh's vertices): the segments
// every sum over rows is built from, and the shard of whole segments that a
// part of a distributed run holds. Plain values, fixed by the row count.
#pragma once
#include <Eigen/Core>
#include <algorithm>

namespace prt {

// Rows are grouped in segments of this many; a part of a run holds whole
// segments. Segments are also the leaves of the fixed sum tree
// (prt/row_parts.hpp), so they are fixed by the row count alone.
constexpr Eigen::Index kSegmentRows = 8192;

// The rows [first, last) of `total` that a part holds.
struct Shard {
  Eigen::Index first = 0, last = 0, total = 0;
  Eigen::Index rows() const { return last - first; }
};

// Part `part` of `parts`: whole segments, as evenly as they divide.
Shard shard_of(Eigen::Index total, int part, int parts);
inline Shard whole(Eigen::Index total) {
  return {0, total, total};
}

// Segment s's rows [begin, end) of the whole signal.
inline Eigen::Index segment_begin(Eigen::Index s) {
  return s * kSegmentRows;
}
inline Eigen::Index segment_end(Eigen::Index s, Eigen::Index total) {
  return std::min(total, (s + 1) * kSegmentRows);
}

}  // namespace prt
