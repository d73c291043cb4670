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
#include "prt/row_parts.hpp"

namespace prt {

// partial(segment) (prt/row_parts.hpp) is called only for segments of
// `shard`, possibly in parallel. The result is on every rank.
std::vector<double> segment_sum(const Shard& shard, const SegmentPartial& partial,
                                const Communicator& comm);

// The same for sums of blocks keyed by an id (e.g. one scatter matrix per
// cluster): a segment returns the blocks of the ids it touches, absent ids
// count as zero, so partials stay as small as the segment's content.
Blocks segment_sum_blocks(const Shard& shard, const SegmentBlocks& partial,
                          const Communicator& comm);

// The sum of one value per local row of `shard` (per_row[0] is row
// shard.first) over the whole signal: 0 when it has no rows.
double segment_sum_rows(const Shard& shard, const std::vector<double>& per_row,
                        const Communicator& comm);

}  // namespace prt
