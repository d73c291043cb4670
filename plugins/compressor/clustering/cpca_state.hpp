// Iterative and adaptive CPCA's state between two passes, kept in a bake's
// checkpoint so that a killed compression resumes where it was and gives
// the bits an uninterrupted run gives (issue 15). The labels go first, in
// one of two parts by the sequence number's parity and led by it (one per
// rank under prt-mpi); the state that names them last: a kill between the
// writes leaves the previous state whole.
#pragma once
#include <optional>

#include "prt/clustering.hpp"
#include "prt/part_keeper.hpp"

namespace prt::clustering {

struct CpcaState {
  int phase = 0;                     // 0: adding components one at a time; 1: adaptive passes
  int component = 1;                 // phase 0: the component count of the next pass
  int iteration = 0;                 // the next pass's index within its component (or phase 1)
  int sequence = 0;                  // counts the states kept by one encode
  std::vector<std::int32_t> labels;  // the labelling the next pass starts from
  std::vector<std::int32_t> fitted_labels;  // the labelling `models` were fitted to
  std::vector<ClusterModel> models;         // the refitter's models (kept when unchanged)
};

// Each rank keeps its shard's labels (parts named by the shard's rows), then
// rank 0 the models and position once every rank's are written. False on
// every rank when any could not write (a full disk ends the keeping, not the
// encode).
bool keep_cpca_state(const PartKeeper& store, const Rows& rows, const CpcaState& state);

// The kept state when it fits this run's rows (this rank's shard), k
// clusters and the rows' columns (else none).
std::optional<CpcaState> kept_cpca_state(const PartKeeper& store, const Rows& rows, int k);

}  // namespace prt::clustering
