// The stages of a bake on plain values, and how they are run: whole, slab by
// slab through a checkpoint, or sharded over ranks.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "prt/bake_file.hpp"
#include "prt/bake_plan.hpp"
#include "prt/frame.hpp"
#include "prt/run_options.hpp"
#include "prt/transport.hpp"

namespace prt {

class RayCaster;
class Progress;

// Stages of a bake; each takes plain values and returns one.
// 1. Rays: visibility (and hits) over the scene's direction set; projects
//    while tracing when nothing needs the bits.
TransportResult trace_stage(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                            const RunOptions& options);
// Stage 2's result: the transfer, the light basis its rows are in (the
// plan's, or the one fitted here: the plan is never changed), the direct
// part before any bounce (when asked for and the plan bounces; empty
// otherwise), and what the stage took and found.
struct TransferOutcome {
  TransferSignal transfer;
  TransferSignal direct;
  std::shared_ptr<const Basis> basis;
  StageTimes times;
  std::map<std::string, double> metrics;
  std::uint64_t rays_cast = 0;
  // A distributed bake of a transfer that couples vertices
  // (coupled_shard_transfer): `transfer` holds this rank's shard's rows,
  // this the whole transfer, which rank 0 writes. Null otherwise.
  std::shared_ptr<TransferSignal> whole;
};
// 2. Transfer: fit (data-driven bases), project, bounces, subsurface, glossy
//    matrices, glossy bounces. Consumes the visibility and hits.
TransferOutcome transfer_stage(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               TransportResult traced, const RunOptions& options,
                               bool want_direct = false);
// 2'. The same per distinct colour-channel material (plan.channels), the
//    rays traced once; the transfers stacked in each row.
TransferOutcome channel_transfers(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                                  TransportResult traced, const RunOptions& options,
                                  bool want_direct = false);
// 2''. A transfer that each vertex gets alone (no fitted basis, bounces,
//    subsurface light or per-channel transfers) in slabs of vertices:
//    vertices [first, last) traced and projected (glossy: their matrices).
bool per_vertex_transfer(const BakePlan& plan);
// The same but for a fitted basis: once fitted, each vertex's row is its own.
bool per_vertex_transfer_after_fit(const BakePlan& plan);
// A diffuse transfer with a fitted basis and nothing that couples vertices:
// its visibility is traced in slabs and kept, the basis fitted (with its own
// checkpoints), and the rows projected (fitted_shard_transfer).
bool fitted_per_vertex_transfer(const BakePlan& plan);
// Either: a transfer whose rows are computed (and can be kept) apart.
bool transfer_by_rows(const BakePlan& plan);
TransferOutcome slab_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                              const RayCaster* caster, const std::vector<Frame>& frames,
                              std::size_t first, std::size_t last, Progress* progress = nullptr);
// Stages 1-2 through options.checkpoint: slab by slab when the transfer is
// per-vertex, else whole (with the fitted basis); parts already kept are
// loaded, not computed. Without a checkpoint: trace_stage + transfer_stage.
// on_disk (a per-vertex transfer only): the rows go to a RowFile in the
// checkpoint folder instead of memory.
TransferOutcome checkpointed_transfer(const BakePlan& plan, const Mesh& mesh,
                                      const DirectionSet& set, const RunOptions& options,
                                      bool want_direct = false, bool on_disk = false);
// A distributed bake's stages 1-2: the ranks trace the slabs of a per-vertex
// transfer as each comes free, into options.checkpoint (a folder every rank
// sees); then each takes its shard's rows from the slabs. rays_cast: all ranks'.
TransferOutcome shard_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               const RunOptions& options, const Shard& shard,
                               const Communicator& comm, bool on_disk = false);
// The same for a transfer that couples vertices (bounces, subsurface light):
// the ranks share each stage's slabs (the trace's, each bounce's, the
// subsurface term's, the glossy matrices'), kept in options.checkpoint, and
// every rank reads the others' after each stage, so that each holds the
// whole transfer (TransferOutcome::whole) as one process computes it, bit
// for bit; `transfer` is the shard's rows, for the compressor.
TransferOutcome coupled_shard_transfer(const BakePlan& plan, const Mesh& mesh,
                                       const DirectionSet& set, const RunOptions& options,
                                       const Shard& shard);
// The same for a fitted basis (fitted_per_vertex_transfer): each rank traces
// its shard's visibility in slabs, the ranks fit the basis together
// (Basis::can_fit_distributed; one process: shard = whole, comm = solo()),
// and each projects its rows. The bits' slabs, the fit's own state, the
// fitted basis and each shard's rows are kept in options.checkpoint.
TransferOutcome fitted_shard_transfer(const BakePlan& plan, const Mesh& mesh,
                                      const DirectionSet& set, const RunOptions& options,
                                      const Shard& shard, const Communicator& comm,
                                      bool on_disk = false);
// Every rank's rows as rank 0 writes the file (`plan`: with the fitted
// basis, as stage 2 returned it): its own from memory, the
// other ranks' read from the checkpoint's slabs a slab at a time (rank 0
// never holds the whole transfer). `store` must outlive the result.
BakeData::StreamedRows kept_transfer(const BakePlan& plan, const CheckpointStore& store,
                                     std::size_t vertices, std::size_t slab_vertices,
                                     std::shared_ptr<const TransferSignal> own);
// The same when each rank kept its shard's rows (fitted_shard_transfer).
BakeData::StreamedRows kept_shard_transfer(const BakePlan& plan, const CheckpointStore& store,
                                           std::size_t vertices, int ranks,
                                           std::shared_ptr<const TransferSignal> own);

// Probes (docs/receivers.md): stages 1-2 for the probes of `grid` over the
// scene's mesh, slab by slab through options.checkpoint when there is one
// (the ranks of a distributed bake taking slabs as they come free), else at
// once. The outcome holds the shard's rows; `valid` every probe's flag.
struct ProbeStage {
  TransferOutcome outcome;
  std::vector<std::uint8_t> valid;
};
ProbeStage probe_shard_transfer(const BakePlan& plan, const Mesh& scene, const ProbeGrid& grid,
                                const DirectionSet& set, double invalid_fraction,
                                const RunOptions& options, const Shard& shard);

// 3. Compression (or the basis's sparse approximation), in the rendered metric.
CompressedTransfer compress_stage(const BakePlan& plan, const TransferSignal& transfer,
                                  const Mesh& mesh, const SourceLocation& where,
                                  const RenderedMetric& metric, const Distribution& shard = {});

// Writes a compression report into bake-file metrics.
void record(const CompressionReport& report, std::map<std::string, double>& metrics);

}  // namespace prt
