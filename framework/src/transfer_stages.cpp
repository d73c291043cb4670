// Stages 1-3 of a bake on plain values: rays, transfer (fit, project,
// bounces, subsurface, glossy matrices, colour channels) and compression.
#include <algorithm>
#include <cstdio>

#include "prt/bake_stages.hpp"
#include "prt/basis.hpp"
#include "prt/bounce_passes.hpp"
#include "prt/checkpoint.hpp"
#include "prt/compressor.hpp"
#include "prt/glossy.hpp"
#include "prt/glossy_interreflection.hpp"
#include "prt/interreflection.hpp"
#include "prt/progress.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/subsurface.hpp"
#include "prt/transport.hpp"
#include "run/coupled_slabs.hpp"
#include "run/kept_state.hpp"

namespace prt {

void record(const CompressionReport& r, std::map<std::string, double>& metrics) {
  metrics["squared_error"] = r.squared_error;
  if (r.rendered_metric) metrics["squared_error_in_rendered_metric"] = 1;
  metrics["vertex_squared_error_p50"] = r.vertex_error_p50;
  metrics["vertex_squared_error_p90"] = r.vertex_error_p90;
  metrics["vertex_squared_error_p99"] = r.vertex_error_p99;
  metrics["vertex_squared_error_max"] = r.vertex_error_max;
  metrics["stored_floats"] = r.stored_floats;
  metrics["stored_bytes"] = r.stored_bytes;
  metrics["clusters"] = double(r.clusters);
  metrics["overdraw"] = r.overdraw;
  metrics["supercluster_overdraw"] = r.supercluster_overdraw;
  for (const auto& [name, value] : r.statistics) metrics[name] = value;
}

TransportResult trace_stage(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                            const RunOptions& options) {
  TransportOptions transport;
  transport.shadowed = plan.shadowed;
  transport.keep_hits = plan.bounces > 0;
  transport.keep_visibility = plan.keep_visibility;
  if (options.traced) {  // a sweep traced these rays once for many configurations
    TransportResult result;
    result.visibility = options.traced->visibility;
    result.hits = options.traced->hits;
    if (result.visibility.vertices() != mesh.vertex_count() ||
        result.visibility.directions() != static_cast<std::size_t>(set.size()) ||
        (transport.keep_hits && result.hits.size() != mesh.vertex_count()))
      throw Error("bake: the traced visibility does not match the scene's mesh and directions");
    return result;
  }
  Progress progress("bake transfer", double(mesh.vertex_count()), transport.shadowed ? "rays" : "",
                    options.quiet);
  std::optional<RayCaster> surfaces;  // rows that are not the mesh's vertices (texels)
  if (plan.occluders && plan.shadowed) transport.caster = &surfaces.emplace(*plan.occluders);
  return transport.keep_visibility
             ? diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress)
             : diffuse_transfer(mesh, set, *plan.basis, transport, &progress);
}

namespace {

// Each bounce's state is kept in the bake's checkpoint (when it has one).
BounceCheckpoint bounce_checkpoint(const RunOptions& options) {
  return {options.checkpoint, options.checkpoint_prefix,
          [&options](const std::string& text) { options.message(text); }, options.slab_vertices,
          options.comm};
}

// The fitted basis, or the one a killed run kept once its fit ended. The fit
// keeps its own state in the checkpoint as it goes (eigentransport: after
// each power iteration).
std::shared_ptr<const Basis> fit_basis(const BakePlan& plan, const Mesh& mesh,
                                       const DirectionSet& set, const VisibilityBits& visibility,
                                       const RunOptions& options, StageTimes& times) {
  const CheckpointStore* store = options.checkpoint;
  if (store && store->has(kFittedBasisMarker)) {
    options.message("resuming: the fitted basis kept in " + store->folder().string());
    return kept_basis(*store, plan.new_basis);
  }
  Stopwatch clock;
  FitData fit{&mesh, &set, &visibility};
  fit.checkpoint = store;
  auto fitted = fit_fresh_basis(plan.new_basis, plan.basis_record.name, fit, store);
  times.add("fit basis (" + plan.basis_record.name + ")", clock.seconds());
  return fitted;
}

void add_bounces(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                 TransportResult& result, const RunOptions& options,
                 std::map<std::string, double>& metrics) {
  Progress progress("inter-reflection", plan.bounces, "", options.quiet);
  BouncedTransfer light = bounce_passes(result.transfer.coefficients, plan.bounces,
                                        diffuse_bounce(mesh, set, result.hits, plan.bounce_albedo),
                                        &progress, bounce_checkpoint(options));
  // How much the bounces add per vertex (transfer norm with / without - 1):
  // near zero on convex parts, large in concave ones.
  std::vector<double> gain(static_cast<std::size_t>(light.total.rows()));
  for (Eigen::Index p = 0; p < light.total.rows(); ++p)
    gain[p] =
        light.total.row(p).norm() / std::max(1e-30f, result.transfer.coefficients.row(p).norm()) -
        1.0;
  std::sort(gain.begin(), gain.end());
  for (const auto& [name, q] : {std::pair{"p50", 0.5}, {"p90", 0.9}, {"p99", 0.99}})
    metrics[std::string("bounce_gain_") + name] =
        gain.empty() ? 0.0 : gain[std::size_t(q * double(gain.size() - 1))];
  metrics["bounce_gain_max"] = gain.empty() ? 0.0 : gain.back();
  char line[200];
  std::snprintf(line, sizeof line,
                "inter-reflection: transfer gain per vertex median %.1f%%, 90th %.1f%%, "
                "99th %.1f%%, max %.1f%%",
                100 * metrics["bounce_gain_p50"], 100 * metrics["bounce_gain_p90"],
                100 * metrics["bounce_gain_p99"], 100 * metrics["bounce_gain_max"]);
  options.message(line);
  result.transfer.coefficients = std::move(light.total);
  for (std::size_t b = 0; b < light.bounce_norms.size(); ++b)
    metrics["bounce_" + std::to_string(b + 1) + "_norm"] = light.bounce_norms[b];
  result.hits = HitLists();
}

}  // namespace

namespace {

// The glossy matrices M_p of every vertex (slab by slab through a checkpoint).
TransferSignal glossy_matrices(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               const TransportResult& result, const std::vector<Frame>& frames,
                               const RunOptions& options, StageTimes& times) {
  Stopwatch clock;
  Progress progress("glossy matrices", double(mesh.vertex_count()), "", options.quiet);
  TransferSignal transfer =
      slabbed_glossy_transfer(plan, mesh, set, result.visibility, frames, options, &progress);
  times.add("glossy matrices (" + std::to_string(plan.glossy_operator.rows()) + "x" +
                std::to_string(plan.basis->size()) + ")",
            clock.seconds());
  return transfer;
}

// Glossy inter-reflection over the shadow pass's hits, added to `transfer`;
// each bounce's share of the direct transfer is reported and kept in metrics.
void add_glossy_bounces(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                        const TransportResult& result, const std::vector<Frame>& frames,
                        TransferSignal& transfer, const RunOptions& options, StageTimes& times,
                        std::map<std::string, double>& metrics) {
  Stopwatch clock;
  Progress bounce_progress("glossy inter-reflection", plan.bounces, "", options.quiet);
  BouncedTransfer light =
      bounce_passes(transfer.coefficients, plan.bounces,
                    glossy_bounce_function(mesh, set, result.hits, *plan.exit, plan.glossy_operator,
                                           plan.basis->size(), frames, plan.bounce_albedo),
                    &bounce_progress, bounce_checkpoint(options));
  const double direct_norm = transfer.coefficients.cast<double>().norm();
  transfer.coefficients = std::move(light.total);
  char line[200];
  std::snprintf(line, sizeof line, "glossy inter-reflection: %d bounces", plan.bounces);
  std::string text = line;
  for (std::size_t b = 0; b < light.bounce_norms.size(); ++b) {
    metrics["bounce_" + std::to_string(b + 1) + "_norm"] = light.bounce_norms[b];
    std::snprintf(line, sizeof line, "%s bounce %zu %.2f%%", b ? "," : ";", b + 1,
                  100 * light.bounce_norms[b] / std::max(direct_norm, 1e-300));
    text += line;
  }
  options.message(text + " of the direct transfer's norm");
  times.add("glossy inter-reflection (" + std::to_string(plan.bounces) + " bounces)",
            clock.seconds());
}

// The subsurface term is view-independent exit radiance: the constant
// function's exit coefficients times the scattered transfer vector. It is
// added after the bounces: subsurface light does not bounce (nor in the
// ground truth).
void add_glossy_subsurface(const GlossyOperator& glossy, const MatrixXfRow& scattered,
                           TransferSignal& t) {
  if (scattered.size() == 0) return;
  const Eigen::Index n_i = scattered.cols();
  for (int r = 0; r < glossy.rows(); ++r)
    t.coefficients.middleCols(r * n_i, n_i) += static_cast<float>(glossy.constant[r]) * scattered;
}

// Glossy transfer: matrices, bounces, then the subsurface term.
TransferSignal glossy_stage(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                            const TransportResult& result, const MatrixXfRow& scattered,
                            const RunOptions& options, StageTimes& times,
                            std::map<std::string, double>& metrics, TransferSignal* direct) {
  const std::vector<Frame> frames = tangent_frames(mesh);
  TransferSignal transfer = glossy_matrices(plan, mesh, set, result, frames, options, times);
  if (plan.bounces > 0) {
    if (direct) {
      *direct = transfer;
      add_glossy_subsurface(plan.glossy_operator, scattered, *direct);
    }
    add_glossy_bounces(plan, mesh, set, result, frames, transfer, options, times, metrics);
  }
  add_glossy_subsurface(plan.glossy_operator, scattered, transfer);
  return transfer;
}

}  // namespace

TransferOutcome transfer_stage(const BakePlan& given, const Mesh& mesh, const DirectionSet& set,
                               TransportResult result, const RunOptions& options,
                               bool want_direct) {
  TransferOutcome out;
  out.rays_cast = result.rays_cast;
  StageTimes& times = out.times;
  std::map<std::string, double>& metrics = out.metrics;
  TransferSignal* direct = want_direct && given.bounces > 0 ? &out.direct : nullptr;
  Stopwatch clock;
  // A fitted basis flows forward in a plan of its own.
  const BakePlan plan =
      given.fit ? given.with_basis(fit_basis(given, mesh, set, result.visibility, options, times))
                : given;
  out.basis = plan.basis;
  // Projected from the bits when they were kept (or traced before by a sweep).
  const bool have_bits =
      result.visibility.vertices() == mesh.vertex_count() && result.visibility.vertices() > 0;
  if (have_bits && (!plan.glossy || plan.subsurface)) {
    clock = Stopwatch();
    result.transfer = project_visibility(mesh, set, result.visibility, *plan.basis);
    times.add("project", clock.seconds());
  }
  if (plan.bounces > 0 && !plan.glossy) {
    if (direct) {  // without bounces, as the bake would be with bounces = 0
      *direct = result.transfer;
      if (plan.subsurface)
        direct->coefficients += slabbed_subsurface(
            mesh, direct->coefficients, plan.subsurface_material, options, "subsurface-direct");
    }
    clock = Stopwatch();
    add_bounces(plan, mesh, set, result, options, metrics);
    times.add("inter-reflection (" + std::to_string(plan.bounces) + " bounces)", clock.seconds());
  }
  MatrixXfRow scattered;
  if (plan.subsurface) {
    clock = Stopwatch();
    scattered = slabbed_subsurface(mesh, result.transfer.coefficients, plan.subsurface_material,
                                   options, "subsurface");
    times.add("subsurface (hierarchical diffusion)", clock.seconds());
  }
  if (plan.glossy) {
    out.transfer =
        glossy_stage(plan, mesh, set, result, scattered, options, times, metrics, direct);
    return out;
  }
  if (plan.subsurface) result.transfer.coefficients += scattered;
  out.transfer = std::move(result.transfer);
  return out;
}

namespace {

// Blocks side by side: row p = [parts[0].row(p) | parts[1].row(p) | ...].
TransferSignal stack_channels(const std::vector<TransferSignal>& parts,
                              const MaterialChannels& channels) {
  TransferSignal out = parts.front();
  Eigen::Index width = 0;
  for (const auto& part : parts) width += part.dimension();
  out.coefficients.resize(parts.front().vertices(), width);
  Eigen::Index at = 0;
  for (const auto& part : parts) {
    out.coefficients.middleCols(at, part.dimension()) = part.coefficients;
    at += part.dimension();
  }
  out.channel_groups = static_cast<int>(parts.size());
  out.group_of_channel = channels.group_of_channel;
  return out;
}

// A channel transfer kept by an earlier run (its direct part and metrics too;
// the fitted basis when this channel fitted it).
TransferOutcome kept_channel(const BakePlan& channel, const CheckpointStore& store,
                             const std::string& prefix, bool want_direct) {
  TransferOutcome out;
  TransferSignal& part = out.transfer;
  part.kind = channel.glossy ? "glossy" : "diffuse";
  part.exit_rows = channel.glossy ? channel.glossy_operator.rows() : 1;
  part.coefficients = store.load_floats(prefix + "transfer");
  if (want_direct) {
    out.direct = part;
    out.direct.coefficients = store.load_floats(prefix + "direct");
  }
  read_metrics(store.load_text(prefix + "metrics"), out.metrics);
  out.basis = channel.fit ? kept_basis(store, channel.new_basis) : channel.basis;
  return out;
}

// Keeps a finished channel transfer; its stages' own parts are done with.
void keep_channel(const CheckpointStore& store, const std::string& prefix,
                  const TransferSignal& part, const TransferSignal* direct,
                  const std::map<std::string, double>& metrics) {
  if (direct) store.save(prefix + "direct", direct->coefficients);
  store.save_text(prefix + "metrics", metrics_text(metrics));
  store.save(prefix + "transfer", part.coefficients);  // last: marks it kept
  for (const std::string& name : store.parts())
    for (const char* stage : {"bounce-", "glossy.", "subsurface"})
      if (name.rfind(prefix + stage, 0) == 0) store.remove_part(name);
}

}  // namespace

TransferOutcome channel_transfers(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                                  TransportResult traced, const RunOptions& options,
                                  bool want_direct) {
  const MaterialChannels& channels = plan.channels;
  std::string which;
  for (int c = 0; c < 3; ++c)
    which += std::string(c ? ", " : "") + "RGB"[c] + " -> " +
             std::to_string(channels.group_of_channel[std::size_t(c)] + 1);
  options.message("colour material: " + std::to_string(channels.groups.size()) +
                  " transfers, one per distinct channel (" + which + ")");
  want_direct = want_direct && plan.bounces > 0;
  TransferOutcome out;
  out.rays_cast = traced.rays_cast;
  out.basis = plan.basis;
  std::vector<TransferSignal> parts, directs;
  for (std::size_t g = 0; g < channels.groups.size(); ++g) {
    // The basis is shared: fitted once, by the first channel, to the same
    // rays; the others take the fitted one.
    BakePlan channel = plan.with_basis(out.basis);
    channel.fit = plan.fit && g == 0;
    const ChannelMaterial& material = channels.groups[g];
    channel.brdf = material.brdf;
    channel.bounce_albedo = material.bounce_albedo;
    channel.subsurface_material = material.subsurface;
    if (channel.glossy)
      channel.glossy_operator =
          GlossyOperator::make(channel.brdf, *channel.exit, channel.incident_order,
                               channel.least_squares, channel.cutoff);
    // Each channel's transfer is kept once done; its stages keep their own
    // parts (bounces) under its prefix.
    RunOptions channel_options = options;
    channel_options.checkpoint_prefix =
        options.checkpoint_prefix + "channel-" + std::to_string(g + 1) + ".";
    const std::string& prefix = channel_options.checkpoint_prefix;
    const CheckpointStore* store = options.checkpoint;
    TransferOutcome part;
    if (store && store->has(prefix + "transfer")) {
      options.message("resuming: channel transfer " + std::to_string(g + 1) + " of " +
                      std::to_string(channels.groups.size()) + " kept in " +
                      store->folder().string());
      part = kept_channel(channel, *store, prefix, want_direct);
    } else {
      // The rays are traced once; every channel but the last works on a copy.
      TransportResult rays = g + 1 < channels.groups.size() ? traced : std::move(traced);
      part = transfer_stage(channel, mesh, set, std::move(rays), channel_options, want_direct);
      if (store)
        keep_channel(*store, prefix, part.transfer, want_direct ? &part.direct : nullptr,
                     part.metrics);
    }
    out.times.append(part.times);
    for (const auto& [name, value] : part.metrics) out.metrics[name] = value;
    out.basis = part.basis;
    parts.push_back(std::move(part.transfer));
    if (want_direct) directs.push_back(std::move(part.direct));
  }
  if (want_direct) out.direct = stack_channels(directs, channels);
  out.transfer = stack_channels(parts, channels);
  return out;
}

CompressedTransfer compress_stage(const BakePlan& plan, const TransferSignal& transfer,
                                  const Mesh& mesh, const SourceLocation& where,
                                  const RenderedMetric& metric, const Distribution& shard) {
  Distribution here = shard;
  here.parts = shard.row_parts(transfer.vertices());
  try {
    if (plan.sparse_terms > 0) {  // a sparse approximation keeps its terms per channel transfer
      CompressedTransfer sparse =
          keep_largest(transfer, plan.sparse_terms * transfer.channel_groups);
      gather_rows(here, sparse);
      return sparse;
    }
    std::optional<TransferSignal> loaded;
    return encode_in_metric(
        *plan.compressor,
        readable_signal(*plan.compressor, plan.compressor_record.name, transfer, loaded), &mesh,
        here, metric);
  } catch (const std::bad_alloc&) {  // the compressor's own memory is not estimated up front
    throw Error(where, "out of memory while compressing the " +
                           std::to_string(transfer.vertices()) + " x " +
                           std::to_string(transfer.dimension()) + " transfer with compressor \"" +
                           plan.compressor_record.name + "\"");
  }
}

}  // namespace prt
