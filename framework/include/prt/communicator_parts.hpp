// The run layer's RowParts: a rank's shard of the rows, and the fixed-tree
// sums (segment_sum.hpp) and collectives over a Communicator. A single
// process is solo() with the whole signal (single_part).
#pragma once
#include <memory>

#include "prt/communicator.hpp"
#include "prt/row_parts.hpp"

namespace prt {

// `comm` must outlive the result.
std::shared_ptr<const RowParts> parts_over(const Communicator& comm, const Shard& shard);

// This rank's shard of `total` rows, as parts over `comm`.
inline std::shared_ptr<const RowParts> rank_parts(const Communicator& comm, Eigen::Index total) {
  return parts_over(comm, shard_of(total, comm.rank(), comm.size()));
}

}  // namespace prt
