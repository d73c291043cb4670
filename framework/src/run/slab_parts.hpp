// A bake's work kept in a checkpoint slab by slab: the names of a slab's
// parts and the checked loading of each (rows of a transfer, visibility
// bits, counts). Shared by the per-vertex, fitted and coupled paths.
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prt/checkpoint.hpp"
#include "prt/communicator.hpp"
#include "prt/error.hpp"
#include "prt/transport.hpp"
#include "prt/visible_products.hpp"

namespace prt {

// Vertices [first, last): slab k of a grid, cut to a range.
struct SlabRange {
  std::size_t first, last;
  std::size_t size() const { return last - first; }
};

// The slabs of a grid of `slab` vertices that meet [first, last), cut to it.
std::vector<SlabRange> slabs_of(std::size_t first, std::size_t last, std::size_t slab);

// The slabs of a per-vertex transfer: `slab_vertices` rounded up to whole
// blocks of the bake's projection (kProjectionBlock), so that slabs change
// no bit of the rows.
inline std::vector<SlabRange> transfer_slabs(std::size_t first, std::size_t last,
                                             std::size_t slab_vertices) {
  // Capped first: a size past any mesh is one slab, and cannot overflow.
  const std::size_t slab = std::min<std::size_t>(slab_vertices, std::size_t(1) << 48);
  const std::size_t blocks =
      std::max<std::size_t>(1, (slab + kProjectionBlock - 1) / kProjectionBlock);
  return slabs_of(first, last, blocks * kProjectionBlock);
}

// "what.rows-FIRST-LAST": the part `what` of vertices [first, last).
std::string rows_name(const char* what, std::size_t first, std::size_t last);
inline std::string rows_name(const char* what, const SlabRange& slab) {
  return rows_name(what, slab.first, slab.last);
}

// A kept part that does not have the shape its slab needs.
Error misshapen_part(const CheckpointStore& store, const std::string& name,
                     const std::string& holds, const std::string& needs);

// Part `what` of a slab: its rows, refused unless they have the slab's shape.
MatrixXfRow kept_rows(const CheckpointStore& store, const SlabRange& slab, Eigen::Index cols,
                      const char* what = "transfer");

// A count (rays cast) kept as part `what` of a slab.
void keep_count(const CheckpointStore& store, const char* what, const SlabRange& slab,
                std::uint64_t count);
std::uint64_t kept_count(const CheckpointStore& store, const char* what, const SlabRange& slab);

// Visibility bits of a slab (row 0: vertex slab.first) kept as part `what`,
// and their rows [range.first, range.last) copied back into `bits` (whose
// row 0 is vertex range.first).
void keep_bits(const CheckpointStore& store, const char* what, const SlabRange& slab,
               const VisibilityBits& bits);
void copy_kept_bits(const CheckpointStore& store, const SlabRange& slab, const SlabRange& range,
                    std::size_t words, VisibilityBits& bits, const char* what = "bits");

// How many of `slabs` are kept (by `kept`); says "resuming: k of n slabs of
// <label> kept in ..." when any are.
std::size_t say_kept_slabs(const CheckpointStore& store, const std::vector<SlabRange>& slabs,
                           const std::function<bool(const SlabRange&)>& kept,
                           const std::string& label,
                           const std::function<void(const std::string&)>& message);

// A stage's slabs shared by the ranks of a distributed bake, each slab
// computed by one rank (slab i by rank i mod size: the same rows whoever
// computes them) and kept in the shared checkpoint, then read by every rank.
// Null or one rank: every slab is this process's.
struct SlabSharing {
  const Communicator* comm = nullptr;
  bool shared() const { return comm && comm->size() > 1; }
  bool mine(std::size_t slab_index) const {
    return !shared() || int(slab_index % std::size_t(comm->size())) == comm->rank();
  }
  bool root() const { return !shared() || comm->rank() == 0; }
  void barrier() const {
    if (shared()) comm->barrier();
  }
};

// The rows [0, vertices) of a stage, computed slab by slab through the
// checkpoint: a slab kept as part `what` is loaded (`on_kept` hears of it,
// for progress), any other is computed by `compute` and kept (shared: by
// one rank, and then read by all; every rank has read every slab when it
// returns). `message` hears "resuming: k of n slabs of <label> kept in ..."
// when any were.
MatrixXfRow rows_in_slabs(const CheckpointStore& store, const std::string& what,
                          std::size_t vertices, Eigen::Index cols, std::size_t slab_vertices,
                          const std::function<MatrixXfRow(const SlabRange&)>& compute,
                          const std::string& label,
                          const std::function<void(const std::string&)>& message,
                          const std::function<void(const SlabRange&)>& on_kept = {},
                          SlabSharing sharing = {});

}  // namespace prt
