// The bake and view pipelines composed from a scene: the same code serves the
// CLI, the tests and the benchmarks.
#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/checkpoint.hpp"
#include "prt/compressor.hpp"
#include "prt/frame.hpp"
#include "prt/glossy.hpp"
#include "prt/image.hpp"
#include "prt/point_lights.hpp"
#include "prt/registry.hpp"
#include "prt/relight.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/renderer.hpp"
#include "prt/scene.hpp"

namespace prt {

// Named wall-clock timings of the stages of one run, in order.
struct StageTimes {
  std::vector<std::pair<std::string, double>> stages;
  void add(const std::string& name, double seconds) { stages.emplace_back(name, seconds); }
  std::string table() const;
};

struct TransportResult;
class RayCaster;

// How a run reports: progress bars (off when quiet) and one-line messages
// (summaries a user reads), through a callback the app provides.
struct RunOptions {
  bool quiet = false;  // no progress bars
  // Visibility bits (and hits, for bounces) traced before for the same mesh
  // and transport (trace_scene): bake() then casts no rays. Used by sweeps.
  const TransportResult* traced = nullptr;
  // false: the bake keeps the exact transfer as its compressed form (or the
  // basis's sparse approximation); a sweep compresses it later, many ways.
  bool compress = true;
  // Where this run's messages go; unset: the process's log sink (prt/log.hpp),
  // info only when not quiet.
  std::function<void(const std::string&)> log;
  // Finished parts are kept here and found again by a rerun (prt/checkpoint.hpp);
  // transfers each vertex gets alone are then computed in slabs of vertices
  // (slab_vertices rounded up to whole blocks of the projection,
  // kProjectionBlock, so that slabs change no bit of the rows).
  const CheckpointStore* checkpoint = nullptr;
  std::size_t slab_vertices = 65536;
  // Before the names of the parts a stage keeps: a bake of several channel
  // transfers runs the stages once per channel, each under its own prefix.
  std::string checkpoint_prefix;
  // Ranks of a distributed bake (prt-mpi); null: this process alone. Each
  // rank traces and compresses its shard of vertices; rank 0's result is the
  // whole bake, the other ranks' results are empty.
  const Communicator* comm = nullptr;
  // Bytes this bake aims to hold in memory (0: kDefaultMemoryFraction of
  // the machine's). A per-vertex transfer that would not fit beside the
  // mesh and its ray-tracing structure is kept in a file in the checkpoint
  // folder, and compressors read it in passes (prt/row_file.hpp).
  double memory_budget = 0;
  // How often a compressor keeps its state in the checkpoint (seconds).
  double checkpoint_seconds = 60;
  double budget() const;
  void message(const std::string& text) const;
  void warn(const std::string& text) const;
};

// For glossy transfer: a warning when the light vector's top frequency band
// holds more than 60% of band 0's energy (the light basis cannot hold
// the light: it rings, and the glossy lobe shows the rings); empty otherwise
// or for bases without bands.
std::string under_resolved_light(const Eigen::MatrixX3d& light, const std::vector<int>& bands);

// Everything a bake will do, decided and validated from the scene before any
// ray is traced: the plug-ins (created, so their parameters are checked),
// what to keep, fit, project and compress.
struct BakePlan {
  std::shared_ptr<Basis> basis;  // light basis (a sphere basis)
  std::shared_ptr<Basis> exit;   // glossy only: exit basis (a hemisphere basis)
  std::shared_ptr<Compressor> compressor;
  PluginRecord basis_record, exit_record, compressor_record;
  bool glossy = false, subsurface = false, fit = false;
  int bounces = 0;
  double bounce_albedo = 1;
  int sparse_terms = 0;          // > 0: the basis's own sparse approximation replaces compression
  bool keep_visibility = false;  // fitting and glossy matrices need the bits
  bool shadowed = true;
  // Glossy: the BRDF and its incident band limit.
  Brdf brdf;
  int incident_order = 0;
  bool least_squares = true;
  double cutoff = 1e-10;
  GlossyMethod glossy_method = GlossyMethod::rotate_sh;
  GlossyOperator glossy_operator;  // made by plan_bake
  SubsurfaceMaterial subsurface_material;
  // Colour channels that need transfers of their own (one group: the scene's
  // channels agree, and the fields above are its material).
  MaterialChannels channels;
};
BakePlan plan_bake(const SceneSpec& scene, PluginRegistry& registry);

// Stages of a bake; each takes plain values and returns one.
// 1. Rays: visibility (and hits) over the scene's direction set; projects
//    while tracing when nothing needs the bits.
TransportResult trace_stage(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                            const RunOptions& options);
// 2. Transfer: fit (data-driven bases), project, bounces, subsurface, glossy
//    matrices, glossy bounces. Consumes the visibility and hits; metrics
//    gets its figures; `direct` (optional) the transfer before any bounce.
TransferSignal transfer_stage(const BakePlan& plan, const SceneSpec& scene, const Mesh& mesh,
                              const DirectionSet& set, TransportResult traced,
                              const RunOptions& options, StageTimes& times,
                              std::map<std::string, double>& metrics,
                              TransferSignal* direct = nullptr);
// 2'. The same per distinct colour-channel material (plan.channels), the
//    rays traced once; the transfers stacked in each row.
TransferSignal channel_transfers(const BakePlan& plan, const SceneSpec& scene, const Mesh& mesh,
                                 const DirectionSet& set, TransportResult traced,
                                 const RunOptions& options, StageTimes& times,
                                 std::map<std::string, double>& metrics,
                                 TransferSignal* direct = nullptr);
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
TransferSignal slab_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                             const RayCaster* caster, const std::vector<Frame>& frames,
                             std::size_t first, std::size_t last, std::uint64_t& rays_cast,
                             Progress* progress = nullptr);
// Stages 1-2 through options.checkpoint: slab by slab when the transfer is
// per-vertex, else whole (with the fitted basis); parts already kept are
// loaded, not computed. Without a checkpoint: trace_stage + transfer_stage.
// on_disk (a per-vertex transfer only): the rows go to a RowFile in the
// checkpoint folder instead of memory.
TransferSignal checkpointed_transfer(const BakePlan& plan, const SceneSpec& scene, const Mesh& mesh,
                                     const DirectionSet& set, const RunOptions& options,
                                     StageTimes& times, std::map<std::string, double>& metrics,
                                     TransferSignal* direct, std::uint64_t& rays_cast,
                                     bool on_disk = false);
// The share of physical memory a bake's default budget takes.
constexpr double kDefaultMemoryFraction = 0.75;
// Bytes a bake holds per mesh vertex beside its transfer while it traces
// (the mesh, its adjacency and Embree's BVH; measured: docs/scale.md).
constexpr double kMeshBytesPerVertex = 400;
// A distributed bake's stages 1-2: the ranks trace the slabs of a per-vertex
// transfer as each comes free, into options.checkpoint (a folder every rank
// sees); then each takes its shard's rows from the slabs. rays_cast: all ranks'.
TransferSignal shard_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                              const RunOptions& options, StageTimes& times,
                              std::uint64_t& rays_cast, const Shard& shard,
                              const Communicator& comm, bool on_disk = false);
// The same for a fitted basis (fitted_per_vertex_transfer): each rank traces
// its shard's visibility in slabs, the ranks fit the basis together
// (Basis::can_fit_distributed; one process: shard = whole, comm = solo()),
// and each projects its rows. The bits' slabs, the fit's own state, the
// fitted basis and each shard's rows are kept in options.checkpoint.
TransferSignal fitted_shard_transfer(const BakePlan& plan, const Mesh& mesh,
                                     const DirectionSet& set, const RunOptions& options,
                                     StageTimes& times, std::uint64_t& rays_cast,
                                     const Shard& shard, const Communicator& comm,
                                     bool on_disk = false);
// Every rank's rows as rank 0 writes the file: its own from memory, the
// other ranks' read from the checkpoint's slabs a slab at a time (rank 0
// never holds the whole transfer). `store` must outlive the result.
BakeData::StreamedRows kept_transfer(const BakePlan& plan, const CheckpointStore& store,
                                     std::size_t vertices, std::size_t slab_vertices,
                                     std::shared_ptr<const TransferSignal> own);
// The same when each rank kept its shard's rows (fitted_shard_transfer).
BakeData::StreamedRows kept_shard_transfer(const BakePlan& plan, const CheckpointStore& store,
                                           std::size_t vertices, int ranks,
                                           std::shared_ptr<const TransferSignal> own);
// What a scene's bake depends on (scene text, mesh bytes, plug-ins, format):
// the key of its checkpoint.
std::string bake_key(const SceneSpec& scene, const BakePlan& plan);

// Refuses (located at the key) a `components` budget, given by the user, larger
// than the transfer's `dimension` coefficients per vertex; a default beyond it
// is used as far as it goes (the compressor warns).
void refuse_budget_beyond_signal(const Params& params, Eigen::Index dimension,
                                 const std::string& compressor);

// 3. Compression (or the basis's sparse approximation), in the rendered metric
// of the plan's bases (identity for orthonormal ones and sparse approximations).
RenderedMetric rendered_metric(const BakePlan& plan);
// The same for a bake read from its file (its scene text names the bases).
RenderedMetric rendered_metric(const BakeData& data, PluginRegistry& registry);
CompressedTransfer compress_stage(const BakePlan& plan, const TransferSignal& transfer,
                                  const Mesh& mesh, const SourceLocation& where,
                                  const RenderedMetric& metric, const Distribution& shard = {});

// Traces the scene's mesh over its direction set, keeping the visibility
// bits, and the hits when the scene asks for bounces.
TransportResult trace_scene(const SceneSpec& scene, const RunOptions& options);

// plan -> rays -> transfer -> compression, as BakeData. Fills times per stage.
BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times);

// Writes a compression report into bake-file metrics.
void record(const CompressionReport& report, std::map<std::string, double>& metrics);

// Throws unless `transfer` encodes the bake's transfer: one row per vertex,
// valid indices, the bake's coefficients per vertex (and finite values
// when `finite`); `what` leads the message.
void check_encoding(const BakeData& data, const CompressedTransfer& transfer,
                    const std::string& what, bool finite = true);

// Checks that `data` was baked with the scene's bases, material and parameters.
void check_bake_matches(const BakeData& data, const SceneSpec& scene);
// Throws unless the bake's transfer has one column per basis coefficient (per
// exit-basis row for glossy transfer): a file's shape must fit its plug-ins.
void check_bake_dimension(const BakeData& data, const Basis& basis);

struct Rendered {
  Image image;
  Eigen::MatrixX3f vertex_radiance;          // v x 3 including albedo
  std::map<std::string, double> statistics;  // the renderer's (overdraw, draw time, ...)
};

// One relighting of a bake's transfer (its compressed form or another encoding
// of it) for a light vector and camera: the exit basis's values toward the
// camera (glossy) and the radiance each vertex sends to it (albedo included).
struct Relit {
  MatrixXfRow exit_values;  // glossy only: v x N_r
  Eigen::MatrixX3f vertex_radiance;
  // Point lights or per-channel transfers: the sums are made here, and
  // renderers draw vertex_radiance.
  bool summed = false;
};

// What viewing a bake needs, made once: its light basis (fitted state loaded)
// and, for glossy transfer, its exit basis and the vertices' frames. The one
// relight path of render, bench, compare-bases and the viewer.
class Relighting {
 public:
  // Checks the bake against the scene and its plug-ins.
  Relighting(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry);
  const Basis& basis() const { return *basis_; }
  // The light vector of an environment in the light basis ([lighting] window applied).
  Eigen::MatrixX3d light(const Environment& environment) const;
  // Throws unless `transfer` encodes this bake's transfer (vertices,
  // coefficients, indices) and `light` has one finite row per light-basis
  // coefficient: for inputs made elsewhere than the bake (the Python module).
  void check_inputs(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light) const;
  // Lays a transfer out for relighting frame after frame (viewer, bench).
  RelightKernel prepare(const CompressedTransfer& transfer) const;
  Relit relight(const RelightKernel& kernel, const Eigen::MatrixX3d& light,
                const Camera& camera) const;
  Relit relight(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                const Camera& camera) const {
    return relight(prepare(transfer), light, camera);
  }
  // Glossy: the exit basis toward the camera at each vertex (v x N_r); empty
  // for diffuse transfer.
  MatrixXfRow exit_values_toward(const Camera& camera) const;
  // The scene's point lights ([[lighting.point]]), which relight() adds.
  const std::vector<PointLight>& point_lights() const { return point_lights_; }
  void set_point_lights(std::vector<PointLight> lights);
  // From now on, point lights by brute-force re-projection of their caps
  // (`cap_samples` directions per vertex): the reference of the rule.
  void use_brute_force(int cap_samples);
  // How the light basis receives them (one line for logs); empty without lights.
  std::string point_light_rule() const;
  // What the point lights add (v x 3, albedo included); zero without lights.
  Eigen::MatrixX3f point_radiance(const CompressedTransfer& transfer,
                                  const MatrixXfRow* exit_values) const;
  // The renderer's input; points into the bake, `transfer` and `relit`.
  RenderInput input(const CompressedTransfer& transfer, const Relit& relit,
                    const Eigen::MatrixX3d& light, const Camera& camera) const;

 private:
  const SceneSpec& scene_;
  const BakeData& data_;
  // The light as the transfer's dot products need it: G l for a light basis
  // that is not orthonormal (t . G l = int T L), l itself otherwise.
  Eigen::MatrixX3d seen_by_transfer(const Eigen::MatrixX3d& light) const;

  std::shared_ptr<Basis> basis_, exit_;
  Eigen::MatrixXd light_gram_;  // empty for an orthonormal light basis
  std::vector<Frame> frames_;
  std::vector<PointLight> point_lights_;
  std::unique_ptr<PointLightProjector> projector_;
};

// One image: `transfer` (the bake's compressed form or another encoding of
// it) relit under `light` toward `camera` and drawn by `renderer`, over
// `background` when given. render() and the Python module use it.
Rendered render_relit(const Relighting& relighting, Renderer& renderer,
                      const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                      const Camera& camera, const Environment* background,
                      StageTimes* times = nullptr);

// Light projection -> per-cluster constants -> per-vertex sums -> image.
Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times, const RunOptions& options = {});

// Monte Carlo ground truth per vertex (v x 3, albedo included) under
// `lighting` (the scene's map, or its band-limited reconstruction), toward
// the camera for glossy materials.
Eigen::MatrixX3f ground_truth_vertices(const SceneSpec& scene, const Mesh& mesh,
                                       const Environment& lighting, const Camera& camera,
                                       const RunOptions& options);
// Renders the Monte Carlo ground truth with the scene's renderer, under the
// scene's light or `lighting` when given.
Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times,
                             const Environment* lighting = nullptr);

// Per-vertex error statistics of `approximation` against `reference` (v x 3).
struct ErrorStats {
  double rms = 0, relative_rms = 0, p99 = 0, max = 0;
};
ErrorStats vertex_error(const Eigen::MatrixX3f& approximation, const Eigen::MatrixX3f& reference);

}  // namespace prt
