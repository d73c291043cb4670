// Bounce after bounce of light gathered over a mesh (diffuse or glossy
// inter-reflection): each pass maps the previous bounce's transfer to the
// next, and the result is the direct transfer plus every bounce. With a
// checkpoint the state after each bounce is kept, under a prefix (one per
// channel transfer), and within a bounce its rows a slab at a time: a rerun
// continues after the last bounce kept, with the slabs of the next.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "prt/transfer.hpp"

namespace prt {

class CheckpointStore;
class Progress;

struct BouncedTransfer {
  MatrixXfRow total;                 // direct + every bounce
  std::vector<double> bounce_norms;  // Frobenius norm of each bounce's transfer
};

struct BounceCheckpoint {
  const CheckpointStore* store = nullptr;           // null: nothing kept
  std::string prefix;                               // before every part's name
  std::function<void(const std::string&)> message;  // "resuming: ..."
  std::size_t slab_vertices = 65536;  // within a bounce, rows are kept a slab at a time
};

// One bounce: the rows [first, last) of the light `previous` sends on.
using BounceFunction =
    std::function<MatrixXfRow(const MatrixXfRow& previous, std::size_t first, std::size_t last)>;

BouncedTransfer bounce_passes(const MatrixXfRow& direct, int bounces, const BounceFunction& bounce,
                              Progress* progress, const BounceCheckpoint& checkpoint = {});

}  // namespace prt
