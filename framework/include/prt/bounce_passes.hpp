// Bounce after bounce of light gathered over a mesh (diffuse or glossy
// inter-reflection): each pass maps the previous bounce's transfer to the
// next, and the result is the direct transfer plus every bounce. With a
// checkpoint the state after each bounce is kept, under a prefix (one per
// channel transfer), and within a bounce its rows a slab at a time: a rerun
// continues after the last bounce kept, with the slabs of the next.
#pragma once
#include <functional>
#include <string>

#include "prt/bounce.hpp"

namespace prt {

class CheckpointStore;
class Communicator;
class Progress;

struct BounceCheckpoint {
  const CheckpointStore* store = nullptr;           // null: nothing kept
  std::string prefix;                               // before every part's name
  std::function<void(const std::string&)> message;  // "resuming: ..."
  std::size_t slab_vertices = 65536;  // within a bounce, rows are kept a slab at a time
  // A distributed bake's ranks (null: one process): each computes its share
  // of a bounce's slabs and reads the others' from the store; rank 0 keeps
  // the state between bounces.
  const Communicator* comm = nullptr;
};

BouncedTransfer bounce_passes(const MatrixXfRow& direct, int bounces, const BounceFunction& bounce,
                              Progress* progress, const BounceCheckpoint& checkpoint = {});

}  // namespace prt
