// The bake driver: a plan run through its stages (whole, slab by slab or
// sharded), refusing what cannot fit before any ray, into BakeData.
#include "prt/bake.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <optional>

#include "prt/bake_stages.hpp"
#include "prt/checkpoint.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/compressor.hpp"
#include "prt/memory.hpp"
#include "prt/probe_transfer.hpp"
#include "prt/progress.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/texel_atlas.hpp"
#include "prt/transport.hpp"

namespace prt {

namespace {

std::string transport_description(const SceneSpec& scene, const DirectionSet& set) {
  return set.kind + " " + std::to_string(set.size()) + " directions, " +
         (keys::transport::shadowed(scene.transport) ? "shadowed" : "unshadowed") +
         ", seed=" + std::to_string(keys::transport::seed(scene.transport));
}

// Refuses, before any ray, a bake whose largest arrays cannot fit: the
// transfer (twice: exact and decoded; not at all when it is kept on disk),
// visibility bits (kept, or held for the projection) and bounce hits, and
// the basis evaluated at every direction (unless it projects by a fast
// transform).
void require_memory(const SceneSpec& scene, const BakePlan& plan, const Mesh& mesh,
                    const DirectionSet& set, bool keep_visibility, bool on_disk) {
  const double v = double(mesh.vertex_count()), d = double(set.size()),
               n = double(plan.basis->size());
  const double rows = plan.glossy ? double(plan.exit->size()) : 1.0;
  const double groups =
      std::max<double>(1, double(plan.channels.groups.size()));  // channel transfers
  const double dimension = rows * n * groups;
  // The basis at every direction: the projection matrix (unless a fast
  // transform projects), and glossy transfer's weighted light values.
  const bool fast = plan.basis->has_fast_projection(set);
  const double projection = fast ? 0 : d * n * sizeof(double);
  const double glossy_light = plan.glossy ? d * n * sizeof(double) : 0;
  // The transfer twice: exact, and its compressed (or exact) form; channel
  // transfers also hold their parts and direct parts while they are stacked.
  const double copies = on_disk ? 0 : groups > 1 ? 4 : 2;
  // Bits not kept are held a window at a time for the projection.
  const double held_bits = std::min(v, double(kBitsWindow)) * d / 8;
  const double bytes = copies * v * dimension * sizeof(float) + projection + glossy_light +
                       // Channel transfers each work on a copy of the rays' results.
                       (groups > 1 ? 2 : 1) * ((keep_visibility ? v * d / 8
                                                : fast          ? 0
                                                                : held_bits) +
                                               (plan.bounces > 0 ? v * d * 8 : 0));
  const double available = available_memory();
  if (bytes > available) {
    char message[400];
    std::snprintf(message, sizeof message,
                  "this bake needs about %.1f GB (%.0f %s x %.0f coefficients%s, %.0f "
                  "directions), but %.1f GB are available; lower the basis size, rays or %s",
                  bytes / 1e9, v, scene.texels() ? "texels" : "vertices", dimension,
                  rows > 1 ? " per glossy matrix" : "", d, available / 1e9,
                  scene.texels() ? "[receivers] resolution" : "mesh resolution");
    throw Error(scene.basis.where, message);
  }
}

}  // namespace

namespace {

// Whether the transfer's rows go to a file: when the mesh (with its BVH) and
// the transfer together would exceed the memory budget. Only a per-vertex
// transfer can; another is held in memory with a warning.
// rows: this process's (a rank's shard), beside the whole mesh.
// points: bytes of the rows' own points when they are not the mesh's vertices.
bool transfer_on_disk(const BakePlan& plan, const Mesh& mesh, Eigen::Index rows,
                      const RunOptions& options, double points = 0) {
  const double v = double(mesh.vertex_count());
  const double groups = std::max<double>(1, double(plan.channels.groups.size()));
  const double transfer = double(rows) * double(plan.glossy ? plan.exit->size() : 1) *
                          double(plan.basis->size()) * groups * 4;
  const double resident = kMeshBytesPerVertex * v + points, budget = options.budget();
  if (resident + transfer <= budget) return false;
  // A fitted diffuse transfer projects its rows after the fit: they too can go to a file.
  if (!transfer_by_rows(plan) || !options.checkpoint || options.traced) {
    options.warn("the transfer (" + gigabytes(transfer) + ") and mesh (~" + gigabytes(resident) +
                 ") exceed the memory budget of " + gigabytes(budget) +
                 "; this transfer couples vertices (or runs without a checkpoint) and is held in "
                 "memory");
    return false;
  }
  const std::string what =
      double(rows) < v ? "this rank's rows of the transfer (" : "the transfer (";
  options.message(what + gigabytes(transfer) + ") and the mesh (~" + gigabytes(resident) +
                  ") exceed the memory budget of " + gigabytes(budget) +
                  ": the transfer's rows are kept in " + options.checkpoint->folder().string() +
                  " and compressed in passes over them");
  if (resident > budget)
    options.warn("the mesh and its ray-tracing structure alone (~" + gigabytes(resident) +
                 ") exceed the memory budget of " + gigabytes(budget) + "; they stay in memory");
  return true;
}

// The probe grid over the scene's mesh at [receivers] spacing, refused
// (before any allocation or ray) when its rows cannot fit in memory: each
// probe's n_E x n_B floats twice (exact and encoded) and its point.
ProbeGrid probe_grid(const SceneSpec& scene, const BakePlan& plan, const Mesh& mesh) {
  const SourceLocation where = scene.receivers.location(keys::receivers::spacing.name());
  ProbeGrid grid;
  try {
    grid = probe_grid_over(mesh.bounds_min(), mesh.bounds_max(),
                           float(keys::receivers::spacing(scene.receivers)));
  } catch (const Error& e) {
    throw Error(where, e.what());
  }
  const double probes = double(grid.counts[0]) * grid.counts[1] * grid.counts[2];
  const double floats = double(plan.basis->size()) * double(plan.exit->size());
  const double bytes = probes * (2 * floats * sizeof(float) + 32);
  if (probes > double(std::numeric_limits<std::uint32_t>::max()) || bytes > available_memory()) {
    char message[400];
    std::snprintf(message, sizeof message,
                  "section [receivers]: %.0f probes (%d x %d x %d) of %.0f coefficients each need "
                  "about %.1f GB, but %.1f GB are available; raise the spacing, or give [exit] a "
                  "smaller incident basis",
                  probes, grid.counts[0], grid.counts[1], grid.counts[2], floats, bytes / 1e9,
                  available_memory() / 1e9);
    throw Error(where, message);
  }
  return grid;
}

// The texels of the mesh's atlas at [receivers] resolution, with their points.
// Also says how many texels of the atlas hold transfer (also metrics).
Receivers texel_receivers(const SceneSpec& scene, const Mesh& mesh, const RunOptions& options,
                          std::map<std::string, double>& metrics) {
  const SourceLocation where = scene.receivers.location(keys::receivers::resolution.name());
  const std::string file = keys::mesh::file(scene.mesh);
  TexelSamples samples;
  try {
    samples = texel_samples(mesh, int(keys::receivers::resolution(scene.receivers)),
                            file.empty() ? "the generated mesh" : file);
  } catch (const Error& e) {
    throw Error(where, e.what());
  }
  const TexelAtlas& atlas = samples.atlas;
  metrics["texels"] = double(atlas.texels.size());
  metrics["texels_on_borders"] = double(samples.border);
  char text[200];
  std::snprintf(text, sizeof text,
                "%zu texels of a %d x %d atlas (%.0f%% of it; %zu of them along the charts' "
                "borders; the rest of the atlas lies outside every chart)",
                atlas.texels.size(), atlas.width, atlas.height,
                100.0 * double(atlas.texels.size()) / (double(atlas.width) * atlas.height),
                samples.border);
  options.message(text);
  return Receivers::texels_of(std::move(samples));
}

// The encoding's report: into the metrics, and said.
void say_report(const CompressionReport& report, const RunOptions& options, BakeData& data) {
  record(report, data.metrics);
  std::string text = report.text();
  if (!text.empty() && text.back() == '\n') text.pop_back();
  options.message(text);
}

// The rows each rank compresses; the compressor keeps its state in the checkpoint.
Distribution encoding_parts(const Communicator& comm, Eigen::Index rows,
                            const RunOptions& options) {
  Distribution where{rank_parts(comm, rows)};
  where.checkpoint = options.checkpoint;
  where.checkpoint_seconds = options.checkpoint_seconds;
  return where;
}

// Stages 1-2 at probes: this rank's rows; every probe's validity goes into
// data.receivers.
TransferOutcome probe_stage(const SceneSpec& scene, const BakePlan& plan, const DirectionSet& set,
                            const RunOptions& options, const Shard& shard, BakeData& data) {
  ProbeStage probes =
      probe_shard_transfer(plan, data.mesh, data.receivers.grid, set,
                           keys::receivers::invalid_fraction(scene.receivers), options, shard);
  data.receivers.valid = std::move(probes.valid);  // the grid and its points are set
  return std::move(probes.outcome);
}

// The grid and how many of its probes sit inside geometry (also a metric).
void say_probes(const RunOptions& options, BakeData& data) {
  const auto invalid = std::count(data.receivers.valid.begin(), data.receivers.valid.end(), 0);
  data.metrics["probes_invalid"] = double(invalid);
  const ProbeGrid& grid = data.receivers.grid;
  options.message(std::to_string(grid.count()) + " probes (" + std::to_string(grid.counts[0]) +
                  " x " + std::to_string(grid.counts[1]) + " x " + std::to_string(grid.counts[2]) +
                  ", spacing " + std::to_string(grid.spacing) + "), " + std::to_string(invalid) +
                  " inside geometry");
}

// The receivers a scene names other than the mesh's vertices (probes,
// texels), made before any ray.
void make_receivers(const SceneSpec& scene, const BakePlan& plan, const RunOptions& options,
                    BakeData& data, std::map<std::string, double>& metrics) {
  if ((plan.probes || plan.texels) && options.traced)
    throw Error(scene.receivers.location(keys::receivers::kind.name()),
                "section [receivers]: traced visibility serves transfer at vertices; a " +
                    keys::receivers::kind(scene.receivers) + " scene traces its receivers itself");
  if (plan.probes) data.receivers = Receivers::probes_on(probe_grid(scene, plan, data.mesh), {});
  if (plan.texels) data.receivers = texel_receivers(scene, data.mesh, options, metrics);
}

// What a distributed bake cannot do yet, refused before any ray.
void require_distributable(const SceneSpec& scene, const BakePlan& plan,
                           const RunOptions& options) {
  if (plan.fit && !plan.basis->can_fit_distributed())
    throw Error(scene.basis.where,
                "basis \"" + plan.basis_record.name +
                    "\" fits to the traced visibility but cannot fit from shards of it (it "
                    "does not declare can_fit_distributed()): bake it with prt bake");
  if (plan.fit && plan.glossy)
    throw Error(scene.basis.where,
                "a distributed bake fits a basis for diffuse transfer only; this scene is "
                "glossy: bake it with prt bake");
  const bool coupled = !per_vertex_transfer_after_fit(plan);
  if (coupled && plan.channels.groups.size() > 1)
    throw Error(scene.material.location(),
                "a distributed bake of bounces or subsurface light needs one transfer for all "
                "colour channels; this material's channels differ: bake it with prt bake");
  if (coupled && plan.fit)
    throw Error(scene.basis.where,
                "a distributed bake fits a basis only to a transfer each vertex gets alone; "
                "this scene's couples vertices (bounces or subsurface light): bake it with prt "
                "bake");
  if (!options.checkpoint) throw Error("a distributed bake needs a checkpoint folder");
  if (options.traced || !options.compress)
    throw Error("a distributed bake traces and compresses its own shards");
  if (plan.sparse_terms == 0) {
    const std::string why = plan.compressor->why_not_distributed();
    if (!why.empty())
      throw Error(scene.compressor.where, "compressor \"" + plan.compressor_record.name +
                                              "\" cannot run distributed: it " + why);
  }
}

// Stages 1-2 as this run makes them: sharded over ranks (fitted or not), or
// through the checkpoint in one process (the direct part kept for bounces).
TransferOutcome transfer_of(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                            const RunOptions& options, const Shard& shard, bool on_disk) {
  const Communicator& comm = options.comm ? *options.comm : solo();
  if (comm.size() > 1) {
    if (!per_vertex_transfer_after_fit(plan))  // bounces, subsurface light
      return coupled_shard_transfer(plan, mesh, set, options, shard);
    return plan.fit ? fitted_shard_transfer(plan, mesh, set, options, shard, comm, on_disk)
                    : shard_transfer(plan, mesh, set, options, shard, comm, on_disk);
  }
  return checkpointed_transfer(plan, mesh, set, options, plan.bounces > 0, on_disk);
}

// Stages 1-2 at this rank's receivers: probes, or points traced against the
// mesh (its vertices, or the texels' points toward it), in memory or on disk.
TransferOutcome receiver_stage(const SceneSpec& scene, const BakePlan& plan,
                               const DirectionSet& set, const RunOptions& options,
                               const Shard& shard, bool distributed, BakeData& data) {
  // A probe grid's rows fit in memory (12,288 probes x 900 floats: 44 MB).
  if (plan.probes) return probe_stage(scene, plan, set, options, shard, data);
  BakePlan traced = plan;
  if (plan.texels) traced.occluders = &data.mesh;
  // The scene's mesh stays resident beside the rows (at texels: their points too).
  const double points = plan.texels ? 24.0 * double(data.receiver_count()) : 0;
  const bool on_disk = transfer_on_disk(plan, data.mesh, shard.rows(), options, points);
  if (!distributed)
    require_memory(scene, plan, data.row_mesh(), set, plan.keep_visibility || options.traced,
                   on_disk);
  return transfer_of(traced, data.row_mesh(), set, options, shard, on_disk);
}

// A distributed bake's file gets the other ranks' rows from their slabs as
// it is written; rank 0 keeps its own shard.
void stream_from_slabs(const BakePlan& plan, const RunOptions& options, int ranks,
                       TransferSignal transfer, BakeData& data) {
  data.transfer.kind = transfer.kind;
  data.transfer.exit_rows = transfer.exit_rows;
  data.transfer.channel_groups = transfer.channel_groups;
  data.transfer.group_of_channel = transfer.group_of_channel;
  auto own = std::make_shared<const TransferSignal>(std::move(transfer));
  data.streamed_transfer = plan.fit
                               ? kept_shard_transfer(plan, *options.checkpoint,
                                                     data.receiver_count(), ranks, std::move(own))
                               : kept_transfer(plan, *options.checkpoint, data.receiver_count(),
                                               options.slab_vertices, std::move(own));
}

// What the file says of how it was made: scene, transport, plug-ins and
// their fitted states, material.
void describe(const SceneSpec& scene, const BakePlan& plan, const DirectionSet& set,
              const RunOptions& options, BakeData& data) {
  data.scene_file = scene.file.string();
  data.scene_text = scene.text;
  data.transport = transport_description(scene, set);
  data.basis = plan.basis_record;
  data.compressor = plan.compressor_record;
  if (!options.compress && plan.sparse_terms == 0) data.compressor = {kExactRecord, "", ""};
  data.albedo = scene.albedo();
  data.material = scene.material_description();
  data.bounces = plan.bounces;
  data.subsurface = plan.subsurface;
  data.basis_state = plan.basis->save();
  if (plan.glossy || plan.probes) {  // glossy: the hemisphere basis; probes: the incident one
    data.exit = plan.exit_record;
    data.exit_state = plan.exit->save();
  }
}

}  // namespace

BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times) {
  Stopwatch clock;
  const BakePlan plan = plan_bake(scene, registry);
  times.add("load plug-ins", clock.seconds());
  return bake(scene, plan, options, times);
}

BakeData bake(const SceneSpec& scene, const BakePlan& plan, const RunOptions& options,
              StageTimes& times) {
  Stopwatch clock;
  BakeData data;
  data.mesh = scene.load_mesh();
  times.add("load mesh", clock.seconds());

  clock = Stopwatch();
  const DirectionSet set = scene.directions();
  times.add("directions", clock.seconds());

  const Communicator& comm = options.comm ? *options.comm : solo();
  const bool distributed = comm.size() > 1;
  if (distributed) require_distributable(scene, plan, options);
  std::map<std::string, double> receiver_metrics;
  make_receivers(scene, plan, options, data, receiver_metrics);
  // One row per receiver: the mesh's vertices, the texels or the probes.
  const Distribution encode_where =
      encoding_parts(comm, Eigen::Index(data.receiver_count()), options);
  const Shard shard = encode_where.parts->shard();
  TransferOutcome stage = receiver_stage(scene, plan, set, options, shard, distributed, data);
  times.append(stage.times);
  data.metrics = std::move(stage.metrics);
  data.direct = std::move(stage.direct);
  TransferSignal transfer = std::move(stage.transfer);
  // The stages after it take the basis stage 2 returned (fitted, or the plan's).
  const BakePlan fitted = plan.with_basis(stage.basis);
  clock = Stopwatch();
  // Compression minimises the error of what is rendered (after a fit: the
  // fitted basis's metric).
  const RenderedMetric metric = rendered_metric(fitted);
  data.compressed = options.compress || plan.sparse_terms > 0
                        ? compress_stage(fitted, transfer, data.row_mesh(), scene.compressor.where,
                                         metric, encode_where)
                        : exact_form(transfer);
  const double encode_seconds = clock.seconds();
  times.add("compress (" + plan.compressor_record.name + ")", encode_seconds);
  const CompressionReport report =
      measure(transfer, data.compressed, &data.row_mesh(), encode_seconds, encode_where, &metric);
  if (distributed && comm.rank() != 0) return {};  // rank 0 holds the bake
  say_report(report, options, data);
  if (stage.whole)  // every rank computed the whole transfer (bounces, subsurface light)
    data.transfer = std::move(*stage.whole);
  else if (distributed)
    stream_from_slabs(fitted, options, comm.size(), std::move(transfer), data);
  else  // in memory, or in its file (write_bake reads it from there)
    data.transfer = std::move(transfer);
  describe(scene, fitted, set, options, data);
  data.metrics["rays_cast"] = static_cast<double>(stage.rays_cast);
  data.metrics["squared_error"] = report.squared_error;
  data.metrics["stored_floats"] = data.compressed.stored_floats();
  if (plan.probes) say_probes(options, data);
  data.metrics.insert(receiver_metrics.begin(), receiver_metrics.end());
  return data;
}

TransportResult trace_scene(const SceneSpec& scene, const RunOptions& options) {
  const Mesh mesh = scene.load_mesh();
  const DirectionSet set = scene.directions();
  TransportOptions transport;
  transport.shadowed = keys::transport::shadowed(scene.transport);
  transport.keep_visibility = true;
  transport.keep_hits = keys::transport::bounces(scene.transport) > 0;
  Progress progress("trace", double(mesh.vertex_count()), transport.shadowed ? "rays" : "",
                    options.quiet);
  return diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress);
}

BakeData bake_to_file(const SceneSpec& scene, const BakePlan& plan, const BakeTarget& target,
                      RunOptions options, StageTimes& times) {
  const Communicator& comm = options.comm ? *options.comm : solo();
  const bool root = comm.rank() == 0;
  if (root) {
    check_output(target.file, scene.input_files(), target.force);
    if (target.restart) CheckpointStore::discard(target.file.path);
  }
  // Every rank hashes its own scene, plug-ins and mesh file: a rank whose
  // inputs differ from rank 0's is refused when it opens the checkpoint.
  const std::string key = bake_key(scene, plan);
  // Rank 0 makes (or checks) the folder, and holds its lock, before the
  // others open it.
  std::optional<CheckpointStore> checkpoint;
  if (root) {
    checkpoint.emplace(target.file.path, key, target.description);
    checkpoint->remove_temporaries();
  }
  comm.barrier();
  if (!root) checkpoint.emplace(target.file.path, key, "", false);
  options.checkpoint = &*checkpoint;
  BakeData data;
  try {
    data = bake(scene, plan, options, times);
  } catch (...) {
    if (root && checkpoint->parts().empty()) checkpoint->remove();  // nothing to resume: no litter
    throw;
  }
  if (root) {
    Stopwatch clock;
    write_bake(target.file.path, data);
    times.add("write bake file", clock.seconds());
  }
  comm.barrier();  // every rank is done with the checkpoint
  if (root) checkpoint->remove();
  return data;
}

}  // namespace prt
