// Work over rows in fixed blocks: block b is rows [b B, (b + 1) B) of the
// whole signal, whatever the number of threads (or, for a distributed run,
// the rank that holds it). A float GEMM's result for a row depends on the
// shape of the block it is computed in, so blocks that TBB's partitioner
// sizes by the core count made results depend on the core count.
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cstdint>

namespace prt {

// Calls visit(begin, end) for every fixed block of rows [first, last), in
// parallel. Blocks are aligned to multiples of `block` counted from row 0 of
// the whole signal: `first` is where this part of it starts.
template <class Index, class Visit>
void for_each_row_block(Index first, Index last, Index block, const Visit& visit) {
  if (last <= first) return;
  const Index begin_block = first / block, end_block = (last + block - 1) / block;
  tbb::parallel_for(
      tbb::blocked_range<Index>(begin_block, end_block, 1),
      [&](const tbb::blocked_range<Index>& range) {
        for (Index b = range.begin(); b < range.end(); ++b)
          visit(std::max(first, b * block), std::min(last, (b + 1) * block));
      },
      tbb::simple_partitioner());
}

}  // namespace prt
