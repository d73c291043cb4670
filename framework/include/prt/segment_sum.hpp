// Sums over the rows of a signal that give the same bits whatever the number
// of threads or ranks: each segment of kSegmentRows rows gives a partial sum
// (computed in row order by one thread), and partials are added along a fixed
// binary tree over segment indices. A rank computes the largest subtrees
// inside its shard and exchanges only their roots (O(log segments) vectors),
// so the sum costs little communication and equals the single-process one.
#pragma once
#include <functional>
#include <map>
#include <vector>

#include "prt/communicator.hpp"

namespace prt {

// partial(segment) returns the segment's vector (all of one length, or empty
// for zero); it is called only for segments of `shard`, possibly in
// parallel. The result is on every rank.
using SegmentPartial = std::function<std::vector<double>(Eigen::Index segment)>;
std::vector<double> segment_sum(const Shard& shard, const SegmentPartial& partial,
                                const Communicator& comm);

// The same for sums of blocks keyed by an id (e.g. one scatter matrix per
// cluster): a segment returns the blocks of the ids it touches, absent ids
// count as zero, so partials stay as small as the segment's content.
using Blocks = std::map<std::int64_t, std::vector<double>>;
using SegmentBlocks = std::function<Blocks(Eigen::Index segment)>;
Blocks segment_sum_blocks(const Shard& shard, const SegmentBlocks& partial,
                          const Communicator& comm);

// The sum of one value per local row of `shard` (per_row[0] is row
// shard.first) over the whole signal: 0 when it has no rows.
double segment_sum_rows(const Shard& shard, const std::vector<double>& per_row,
                        const Communicator& comm);

// Segment s's rows [begin, end) of the whole signal.
inline Eigen::Index segment_begin(Eigen::Index s) {
  return s * kSegmentRows;
}
inline Eigen::Index segment_end(Eigen::Index s, Eigen::Index total) {
  return std::min(total, (s + 1) * kSegmentRows);
}

}  // namespace prt
