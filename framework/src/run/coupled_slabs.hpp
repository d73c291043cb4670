// The per-vertex work of a transfer that couples vertices (bounces,
// subsurface light, per-channel transfers, a glossy transfer with a fitted
// basis), slab by slab through the bake's checkpoint, so that a killed bake
// loses at most one slab of it. Results equal the whole-mesh stages'.
#pragma once
#include <string>
#include <vector>

#include "prt/frame.hpp"
#include "prt/pipeline.hpp"
#include "prt/subsurface.hpp"
#include "prt/transport.hpp"

namespace prt {

// Vertices [slab.first, slab.last) traced as the plan says: their visibility
// bits (keep_visibility) or their transfer projected while tracing, and the
// hits of their blocked rays (keep_hits). `caster` is shared by many slabs
// (null: unshadowed).
TransportResult trace_slab(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                           const RayCaster* caster, std::size_t first, std::size_t last,
                           bool keep_visibility, bool keep_hits, Progress* progress);

// The trace: what the stages after it need of a slab (its projected rows or
// its visibility bits, and for bounces the hits of its blocked rays) is kept
// as soon as the slab is traced. Equals trace_stage's result.
TransportResult slabbed_trace(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                              const RunOptions& options);

// The glossy matrices M_p from the visibility, kept a slab at a time under
// the options' checkpoint prefix (one per channel transfer); without a
// checkpoint, glossy_transfer of the whole mesh.
TransferSignal slabbed_glossy_transfer(const BakePlan& plan, const Mesh& mesh,
                                       const DirectionSet& set, const VisibilityBits& visibility,
                                       const std::vector<Frame>& frames, const RunOptions& options,
                                       Progress* progress);

// Subsurface scattering s_p of `transfer`, kept a slab at a time as part
// `what` under the options' checkpoint prefix; without a checkpoint,
// subsurface_transfer of the whole mesh.
MatrixXfRow slabbed_subsurface(const Mesh& mesh, const MatrixXfRow& transfer,
                               const SubsurfaceMaterial& material, const RunOptions& options,
                               const std::string& what);

}  // namespace prt
