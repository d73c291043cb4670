#include "prt/pipeline.hpp"

#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "coupled_slabs.hpp"
#include "kept_state.hpp"
#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/checkpoint.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/glossy_interreflection.hpp"
#include "prt/ground_truth.hpp"
#include "prt/interreflection.hpp"
#include "prt/log.hpp"
#include "prt/memory.hpp"
#include "prt/progress.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/renderer.hpp"
#include "prt/row_file.hpp"
#include "prt/subsurface.hpp"
#include "prt/transport.hpp"

namespace prt {

std::string StageTimes::table() const {
  std::string out;
  double total = 0;
  char line[160];
  for (const auto& [name, seconds] : stages) {
    std::snprintf(line, sizeof line, "  %-28s %9.3f s\n", name.c_str(), seconds);
    out += line;
    total += seconds;
  }
  std::snprintf(line, sizeof line, "  %-28s %9.3f s\n", "total", total);
  return out + line;
}

void RunOptions::message(const std::string& text) const {
  if (log)
    log(text);
  else if (!quiet)
    log_info(text);
}

void RunOptions::warn(const std::string& text) const {
  if (log)
    log("warning: " + text);
  else
    log_warning(text);
}

std::string under_resolved_light(const Eigen::MatrixX3d& light, const std::vector<int>& bands) {
  if (bands.size() != static_cast<std::size_t>(light.rows()) || bands.empty()) return "";
  const int top = *std::max_element(bands.begin(), bands.end());
  if (top == 0) return "";
  double band0 = 0, band_top = 0;
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const double energy = light.row(Eigen::Index(i)).squaredNorm();
    if (bands[i] == 0) band0 += energy;
    if (bands[i] == top) band_top += energy;
  }
  if (!(band_top > 0.6 * band0)) return "";
  char text[400];
  std::snprintf(text, sizeof text,
                "the light's top band (l = %d) holds %.0f%% of band 0's energy: the light basis "
                "is too small for this light, which rings, and a glossy lobe shows the rings as "
                "dark seams and blotches; raise [basis] order",
                top, 100 * band_top / std::max(band0, 1e-300));
  return text;
}

namespace {

std::string transport_description(const SceneSpec& scene, const DirectionSet& set) {
  return set.kind + " " + std::to_string(set.size()) + " directions, " +
         (scene.transport.get_bool("shadowed") ? "shadowed" : "unshadowed") +
         ", seed=" + std::to_string(scene.transport.get_int("seed"));
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
                  "this bake needs about %.1f GB (%.0f vertices x %.0f coefficients%s, %.0f "
                  "directions), but %.1f GB are available; lower the basis size, rays or mesh "
                  "resolution",
                  bytes / 1e9, v, dimension, rows > 1 ? " per glossy matrix" : "", d,
                  available / 1e9);
    throw Error(scene.basis.where, message);
  }
}

// "sphere" / "hemisphere" with the role each serves, for domain errors.
std::string domain_error(const PluginChoice& choice, const char* section, Domain wanted) {
  const bool sphere = wanted == Domain::sphere;
  return "[" + std::string(section) + "] basis \"" + choice.name + "\" is defined over the " +
         (sphere ? "hemisphere of a local frame" : "whole sphere") + ", but this role needs a " +
         (sphere ? "sphere" : "hemisphere") +
         " basis: the light basis ([basis]) carries source light and diffuse transfer over the "
         "sphere; the exit basis ([exit], glossy only) carries exit radiance over each vertex's "
         "upper hemisphere";
}

PluginRecord record_of(const PluginChoice& choice, PluginRegistry& registry, PluginKind kind) {
  return {choice.name, registry.find(kind, choice.name).info.version, choice.params.describe()};
}

}  // namespace

double RunOptions::budget() const {
  return memory_budget > 0 ? memory_budget : kDefaultMemoryFraction * physical_memory();
}

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

namespace {

// What the direction set really is, and whether it can resolve the basis:
// a cube map rounds `rays` to 6 R^2, and fewer directions than twice the
// basis's functions alias (unless the set is the basis's own lattice, on
// which its projection is exact).
void warn_if_under_sampled(const SceneSpec& scene, const DirectionSet& set, const Basis& basis,
                           const std::string& name) {
  const std::string where = scene.transport.location("rays").str() + ": ";
  const auto rays = scene.transport.get_int("rays");
  if (set.kind == "cubemap" && set.size() != rays) {
    const int r = static_cast<int>(std::lround(std::sqrt(set.size() / 6.0)));
    log_warning_once(where + "rays = " + std::to_string(rays) + " makes a 6 x " +
                     std::to_string(r) + " x " + std::to_string(r) + " cube map: " +
                     std::to_string(set.size()) + " directions (a cube map has 6 R^2)");
  }
  const auto native = basis.native_directions();
  const bool own_lattice = native && native->kind == set.kind && native->size() == set.size();
  if (!own_lattice && set.size() < 2 * Eigen::Index(basis.size()))
    log_warning_once(where + std::to_string(set.size()) + " directions for basis \"" + name +
                     "\"'s " + std::to_string(basis.size()) +
                     " functions: fewer than twice as many, so the projection aliases; raise "
                     "[transport] rays to " +
                     std::to_string(2 * basis.size()) + " or more");
}

// orthonormal() is a claim the relight relies on (it then applies no
// metric): checked on the basis's rule before any ray, for bases small
// enough that G costs milliseconds (n <= 400) and not fitted to the bake.
void check_orthonormal_claim(const Basis& basis, const PluginChoice& choice) {
  if (!basis.orthonormal() || basis.can_fit() || basis.size() > 400) return;
  const Eigen::MatrixXd g = gram_matrix(basis);
  const double off = (g - Eigen::MatrixXd::Identity(g.rows(), g.cols())).cwiseAbs().maxCoeff();
  if (!(off <= 1e-6)) {
    char text[120];
    std::snprintf(text, sizeof text, "%.3g", off);
    throw Error(choice.where, "basis \"" + choice.name +
                                  "\" says it is orthonormal, but its Gram matrix differs from "
                                  "the identity by " +
                                  text +
                                  " on its own rule; relighting with it would be wrong. Return "
                                  "false from orthonormal() and the framework applies its metric");
  }
}

}  // namespace

void refuse_budget_beyond_signal(const Params& params, Eigen::Index dimension,
                                 const std::string& compressor) {
  if (!params.has("components")) return;
  const SourceLocation &at = params.location("components"), &section = params.location();
  const bool given = at.file != section.file || at.line != section.line ||
                     at.column != section.column;  // a default is located at its section
  std::int64_t components = 0;
  try {
    components = params.get_int("components");
  } catch (const Error&) {
    return;  // not an integer: not the conventional budget key
  }
  if (!given || components <= dimension) return;
  params.fail("components", "compressor \"" + compressor + "\": " + std::to_string(components) +
                                " is more than the transfer's " + std::to_string(dimension) +
                                " coefficients per vertex: each cluster would store more than "
                                "the uncompressed transfer (at most " +
                                std::to_string(dimension) + ")");
}

BakePlan plan_bake(const SceneSpec& scene, PluginRegistry& registry) {
  BakePlan plan;
  PluginChoice basis = scene.basis, compressor = scene.compressor;
  plan.basis = registry.create<Basis>(basis.name, basis.params, basis.where);
  plan.compressor =
      registry.create<Compressor>(compressor.name, compressor.params, compressor.where);
  plan.basis_record = record_of(scene.basis, registry, PluginKind::basis);
  plan.compressor_record = record_of(scene.compressor, registry, PluginKind::compressor);
  if (plan.basis->domain() != Domain::sphere)
    throw Error(basis.where, domain_error(basis, "basis", Domain::sphere));
  scene.check_window(*plan.basis);
  check_orthonormal_claim(*plan.basis, basis);
  try {  // the direction set is cheap to make; its rays come later
    const DirectionSet set = scene.directions();
    plan.basis->check_directions(set);
    warn_if_under_sampled(scene, set, *plan.basis, basis.name);
  } catch (const Error& e) {
    throw Error(scene.transport.location("directions"), e.what());
  }
  plan.sparse_terms = plan.basis->approximation_terms();
  if (plan.sparse_terms > 0 && !plan.compressor->exact())
    throw Error(compressor.where,
                "basis \"" + basis.name +
                    "\" approximates non-linearly (keeps its largest coefficients per vertex); "
                    "that replaces compression, so use an exact compressor such as \"none\" "
                    "(not \"" +
                    compressor.name + "\")");
  plan.glossy = scene.glossy();
  plan.subsurface = scene.material.get_bool("subsurface");
  plan.bounces = static_cast<int>(scene.transport.get_int("bounces"));
  plan.bounce_albedo = scene.bounce_albedo();
  plan.shadowed = scene.transport.get_bool("shadowed");
  plan.fit = plan.basis->can_fit();
  if (plan.glossy) {
    PluginChoice exit = scene.exit;
    plan.exit = registry.create<Basis>(exit.name, exit.params, exit.where);
    plan.exit_record = record_of(scene.exit, registry, PluginKind::basis);
    if (plan.exit->domain() != Domain::hemisphere)
      throw Error(exit.where, domain_error(exit, "exit", Domain::hemisphere));
    check_orthonormal_claim(*plan.exit, exit);
    if (plan.exit->can_fit())
      throw Error(exit.where, "[exit] basis \"" + exit.name +
                                  "\" is data-driven (fits to traced visibility); an exit basis "
                                  "must be fixed before the bake");
    plan.brdf = scene.brdf();
    plan.incident_order = scene.incident_order(*plan.basis);
    plan.least_squares = scene.material.get_string("projection") == "least-squares";
    plan.cutoff = scene.material.get_real("cutoff");
    // Made here, before any ray: it depends only on the BRDF and the exit basis.
    try {
      plan.glossy_operator = GlossyOperator::make(plan.brdf, *plan.exit, plan.incident_order,
                                                  plan.least_squares, plan.cutoff);
    } catch (const Error& e) {
      throw Error(exit.where, e.what());
    }
  }
  plan.subsurface_material = scene.subsurface();
  plan.channels = scene.channels();
  plan.keep_visibility = plan.fit || plan.glossy;
  if (plan.sparse_terms == 0)
    refuse_budget_beyond_signal(
        compressor.params,
        Eigen::Index(plan.basis->size()) * (plan.glossy ? plan.exit->size() : 1) *
            Eigen::Index(std::max<std::size_t>(1, plan.channels.groups.size())),
        compressor.name);
  return plan;
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
  return transport.keep_visibility
             ? diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress)
             : diffuse_transfer(mesh, set, *plan.basis, transport, &progress);
}

namespace {

// Each bounce's state is kept in the bake's checkpoint (when it has one).
BounceCheckpoint bounce_checkpoint(const RunOptions& options) {
  return {options.checkpoint, options.checkpoint_prefix,
          [&options](const std::string& text) { options.message(text); }, options.slab_vertices};
}

// The fitted basis, or the one a killed run kept once its fit ended. The fit
// keeps its own state in the checkpoint as it goes (eigentransport: after
// each power iteration).
void fit_basis(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
               const VisibilityBits& visibility, const RunOptions& options, StageTimes& times) {
  const CheckpointStore* store = options.checkpoint;
  if (store && store->has(kFittedBasisMarker)) {
    load_kept_basis_state(*store, *plan.basis);
    options.message("resuming: the fitted basis kept in " + store->folder().string());
    return;
  }
  Stopwatch clock;
  FitData fit{&mesh, &set, &visibility};
  fit.checkpoint = store;
  plan.basis->fit(fit);
  times.add("fit basis (" + plan.basis_record.name + ")", clock.seconds());
  if (store) keep_fitted_basis(*store, *plan.basis, plan.basis_record.name);
}

void add_bounces(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                 TransportResult& result, const RunOptions& options,
                 std::map<std::string, double>& metrics) {
  Progress progress("inter-reflection", plan.bounces, "", options.quiet);
  Interreflection light =
      interreflect(mesh, set, result.hits, result.transfer.coefficients, plan.bounces,
                   plan.bounce_albedo, &progress, bounce_checkpoint(options));
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

TransferSignal transfer_stage(const BakePlan& plan, const SceneSpec& scene, const Mesh& mesh,
                              const DirectionSet& set, TransportResult result,
                              const RunOptions& options, StageTimes& times,
                              std::map<std::string, double>& metrics, TransferSignal* direct) {
  Stopwatch clock;
  if (plan.fit) fit_basis(plan, mesh, set, result.visibility, options, times);
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
  if (!plan.glossy) {
    if (plan.subsurface) result.transfer.coefficients += scattered;
    return std::move(result.transfer);
  }
  const GlossyOperator& glossy = plan.glossy_operator;
  clock = Stopwatch();
  Progress progress("glossy matrices", double(mesh.vertex_count()), "", options.quiet);
  const std::vector<Frame> frames = tangent_frames(mesh);
  TransferSignal transfer =
      slabbed_glossy_transfer(plan, mesh, set, result.visibility, frames, options, &progress);
  times.add("glossy matrices (" + std::to_string(glossy.rows()) + "x" +
                std::to_string(plan.basis->size()) + ")",
            clock.seconds());
  // The subsurface term is view-independent exit radiance: the constant
  // function's exit coefficients times the scattered transfer vector. It is
  // added after the bounces: subsurface light does not bounce (nor in the
  // ground truth).
  auto add_subsurface = [&](TransferSignal& t) {
    if (!plan.subsurface) return;
    const Eigen::Index n_i = scattered.cols();
    for (int r = 0; r < glossy.rows(); ++r)
      t.coefficients.middleCols(r * n_i, n_i) += static_cast<float>(glossy.constant[r]) * scattered;
  };
  if (plan.bounces > 0) {
    if (direct) {
      *direct = transfer;
      add_subsurface(*direct);
    }
    clock = Stopwatch();
    Progress bounce_progress("glossy inter-reflection", plan.bounces, "", options.quiet);
    GlossyInterreflection light = glossy_interreflect(
        mesh, set, result.hits, transfer.coefficients, *plan.exit, glossy, plan.basis->size(),
        frames, plan.bounces, plan.bounce_albedo, &bounce_progress, bounce_checkpoint(options));
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
  add_subsurface(transfer);
  return transfer;
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

}  // namespace

TransferSignal channel_transfers(const BakePlan& plan, const SceneSpec& scene, const Mesh& mesh,
                                 const DirectionSet& set, TransportResult traced,
                                 const RunOptions& options, StageTimes& times,
                                 std::map<std::string, double>& metrics, TransferSignal* direct) {
  const MaterialChannels& channels = plan.channels;
  std::string which;
  for (int c = 0; c < 3; ++c)
    which += std::string(c ? ", " : "") + "RGB"[c] + " -> " +
             std::to_string(channels.group_of_channel[std::size_t(c)] + 1);
  options.message("colour material: " + std::to_string(channels.groups.size()) +
                  " transfers, one per distinct channel (" + which + ")");
  std::vector<TransferSignal> parts, directs;
  for (std::size_t g = 0; g < channels.groups.size(); ++g) {
    BakePlan channel = plan;
    channel.fit = plan.fit && g == 0;  // the basis is shared: fitted once, to the same rays
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
    TransferSignal channel_direct;
    if (store && store->has(prefix + "transfer")) {
      options.message("resuming: channel transfer " + std::to_string(g + 1) + " of " +
                      std::to_string(channels.groups.size()) + " kept in " +
                      store->folder().string());
      TransferSignal part;
      part.kind = channel.glossy ? "glossy" : "diffuse";
      part.exit_rows = channel.glossy ? channel.glossy_operator.rows() : 1;
      part.coefficients = store->load_floats(prefix + "transfer");
      if (direct) {
        channel_direct = part;
        channel_direct.coefficients = store->load_floats(prefix + "direct");
      }
      read_metrics(store->load_text(prefix + "metrics"), metrics);
      if (channel.fit) load_kept_basis_state(*store, *plan.basis);
      parts.push_back(std::move(part));
    } else {
      // The rays are traced once; every channel but the last works on a copy.
      TransportResult rays = g + 1 < channels.groups.size() ? traced : std::move(traced);
      parts.push_back(transfer_stage(channel, scene, mesh, set, std::move(rays), channel_options,
                                     times, metrics, direct ? &channel_direct : nullptr));
      if (store) {
        if (direct) store->save(prefix + "direct", channel_direct.coefficients);
        store->save_text(prefix + "metrics", metrics_text(metrics));
        store->save(prefix + "transfer", parts.back().coefficients);  // last: marks it kept
        for (const std::string& part : store->parts())  // its stages' parts: done with
          for (const char* stage : {"bounce-", "glossy.", "subsurface"})
            if (part.rfind(prefix + stage, 0) == 0) store->remove_part(part);
      }
    }
    if (direct) directs.push_back(std::move(channel_direct));
  }
  if (direct) *direct = stack_channels(directs, channels);
  return stack_channels(parts, channels);
}

RenderedMetric rendered_metric(const BakePlan& plan) {
  if (plan.sparse_terms > 0) return {};  // the basis's own coefficients are kept
  return RenderedMetric(*plan.basis, plan.glossy ? plan.exit.get() : nullptr);
}

CompressedTransfer compress_stage(const BakePlan& plan, const TransferSignal& transfer,
                                  const Mesh& mesh, const SourceLocation& where,
                                  const RenderedMetric& metric, const Distribution& shard) {
  const Distribution here =
      shard.shard.total == 0 ? Distribution::whole_signal(transfer.vertices()) : shard;
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

namespace {

// Whether the transfer's rows go to a file: when the mesh (with its BVH) and
// the transfer together would exceed the memory budget. Only a per-vertex
// transfer can; another is held in memory with a warning.
// rows: this process's (a rank's shard), beside the whole mesh.
bool transfer_on_disk(const BakePlan& plan, const Mesh& mesh, Eigen::Index rows,
                      const RunOptions& options) {
  const double v = double(mesh.vertex_count());
  const double groups = std::max<double>(1, double(plan.channels.groups.size()));
  const double transfer = double(rows) * double(plan.glossy ? plan.exit->size() : 1) *
                          double(plan.basis->size()) * groups * 4;
  const double resident = kMeshBytesPerVertex * v, budget = options.budget();
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
  if (!per_vertex_transfer_after_fit(plan))
    throw Error(scene.basis.where,
                "a distributed bake needs a transfer each vertex gets alone; this scene's "
                "couples vertices (bounces, subsurface light or per-channel transfers): bake "
                "it with prt bake");
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

}  // namespace

BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times) {
  Stopwatch clock;
  const BakePlan plan = plan_bake(scene, registry);
  times.add("load plug-ins", clock.seconds());

  clock = Stopwatch();
  BakeData data;
  data.mesh = scene.load_mesh();
  times.add("load mesh", clock.seconds());

  clock = Stopwatch();
  const DirectionSet set = scene.directions();
  times.add("directions", clock.seconds());

  const Communicator& comm = options.comm ? *options.comm : solo();
  const bool distributed = comm.size() > 1;
  if (distributed) require_distributable(scene, plan, options);
  const Eigen::Index vertices = static_cast<Eigen::Index>(data.mesh.vertex_count());
  const Distribution shard = distributed
                                 ? Distribution{&comm, shard_of(vertices, comm.rank(), comm.size())}
                                 : Distribution::whole_signal(vertices);
  Distribution encode_where = shard;  // the compressor keeps its state in the checkpoint
  encode_where.checkpoint = options.checkpoint;
  encode_where.checkpoint_seconds = options.checkpoint_seconds;
  const bool on_disk = transfer_on_disk(plan, data.mesh, shard.shard.rows(), options);
  if (!distributed)
    require_memory(scene, plan, data.mesh, set, plan.keep_visibility || options.traced, on_disk);
  std::uint64_t rays_cast = 0;
  TransferSignal transfer =
      distributed
          ? (plan.fit ? fitted_shard_transfer(plan, data.mesh, set, options, times, rays_cast,
                                              shard.shard, comm, on_disk)
                      : shard_transfer(plan, data.mesh, set, options, times, rays_cast, shard.shard,
                                       comm, on_disk))
          : checkpointed_transfer(plan, scene, data.mesh, set, options, times, data.metrics,
                                  plan.bounces > 0 ? &data.direct : nullptr, rays_cast, on_disk);

  clock = Stopwatch();
  // Compression minimises the error of what is rendered (after a fit: the
  // fitted basis's metric).
  const RenderedMetric metric = rendered_metric(plan);
  data.compressed =
      options.compress || plan.sparse_terms > 0
          ? compress_stage(plan, transfer, data.mesh, scene.compressor.where, metric, encode_where)
          : exact_form(transfer);
  const double encode_seconds = clock.seconds();
  times.add("compress (" + plan.compressor_record.name + ")", encode_seconds);
  const CompressionReport report =
      measure(transfer, data.compressed, &data.mesh, encode_seconds, shard, &metric);
  if (distributed && comm.rank() != 0) return {};  // rank 0 holds the bake
  record(report, data.metrics);
  std::string text = report.text();
  if (!text.empty() && text.back() == '\n') text.pop_back();
  options.message(text);
  if (distributed) {  // the file gets the other ranks' rows from their slabs as it is written
    data.transfer.kind = transfer.kind;
    data.transfer.exit_rows = transfer.exit_rows;
    data.transfer.channel_groups = transfer.channel_groups;
    data.transfer.group_of_channel = transfer.group_of_channel;
    auto own = std::make_shared<const TransferSignal>(std::move(transfer));
    data.streamed_transfer =
        plan.fit ? kept_shard_transfer(plan, *options.checkpoint, data.mesh.vertex_count(),
                                       comm.size(), std::move(own))
                 : kept_transfer(plan, *options.checkpoint, data.mesh.vertex_count(),
                                 options.slab_vertices, std::move(own));
  } else {  // in memory, or in its file (write_bake reads it from there)
    data.transfer = std::move(transfer);
  }

  data.scene_file = scene.file.string();
  data.scene_text = scene.text;
  data.transport = transport_description(scene, set);
  data.basis = plan.basis_record;
  data.compressor = plan.compressor_record;
  if (!options.compress && plan.sparse_terms == 0) data.compressor = {"exact", "", ""};
  data.albedo = scene.albedo();
  data.material = scene.material_description();
  data.bounces = plan.bounces;
  data.subsurface = plan.subsurface;
  data.basis_state = plan.basis->save();
  if (plan.glossy) {
    data.exit = plan.exit_record;
    data.exit_state = plan.exit->save();
  }
  data.metrics["rays_cast"] = static_cast<double>(rays_cast);
  data.metrics["squared_error"] = report.squared_error;
  data.metrics["stored_floats"] = data.compressed.stored_floats();
  return data;
}

TransportResult trace_scene(const SceneSpec& scene, const RunOptions& options) {
  const Mesh mesh = scene.load_mesh();
  const DirectionSet set = scene.directions();
  TransportOptions transport;
  transport.shadowed = scene.transport.get_bool("shadowed");
  transport.keep_visibility = true;
  transport.keep_hits = scene.transport.get_int("bounces") > 0;
  Progress progress("trace", double(mesh.vertex_count()), transport.shadowed ? "rays" : "",
                    options.quiet);
  return diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress);
}

namespace {

void check_plugin_matches(const PluginRecord& baked, const PluginChoice& wanted, const char* role) {
  const std::string parameters = wanted.params.describe();
  if (same_plugin(baked.name, baked.parameters, wanted.name, parameters)) return;
  auto first_line = [](const std::string& text) { return text.substr(0, text.find('\n')); };
  throw Error(wanted.where, std::string("the bake file was made with ") + role + " \"" +
                                baked.name + "\" (" + first_line(baked.parameters) +
                                "), but the scene asks for \"" + wanted.name + "\" (" +
                                first_line(parameters) + "); bake again");
}

}  // namespace

void check_bake_matches(const BakeData& data, const SceneSpec& scene) {
  const std::string material = scene.material_description();
  const int bounces = static_cast<int>(scene.transport.get_int("bounces"));
  if (data.material != material || data.bounces != bounces ||
      data.subsurface != scene.material.get_bool("subsurface") ||
      data.transfer.glossy() != scene.glossy())
    throw Error(scene.material.location(),
                "the bake file was made for material \"" + data.material + "\" with " +
                    std::to_string(data.bounces) + " bounces" +
                    (data.subsurface ? " and subsurface" : "") + ", but the scene asks for \"" +
                    material + "\" with " + std::to_string(bounces) + " bounces; bake again");
  check_plugin_matches(data.basis, scene.basis, "basis");
  if (scene.glossy()) check_plugin_matches(data.exit, scene.exit, "exit basis");
}

void check_bake_dimension(const BakeData& data, const Basis& basis) {
  const Eigen::Index expected =
      Eigen::Index(basis.size()) * data.transfer.exit_rows * data.transfer.channel_groups;
  if (data.transfer.dimension() != expected)
    throw Error(data.scene_file + ": the bake's transfer has " +
                std::to_string(data.transfer.dimension()) + " columns, but basis \"" +
                data.basis.name + "\" has " + std::to_string(basis.size()) + " coefficients" +
                (data.transfer.glossy()
                     ? " x " + std::to_string(data.transfer.exit_rows) + " exit rows"
                     : std::string()) +
                (data.transfer.channel_groups > 1
                     ? " x " + std::to_string(data.transfer.channel_groups) + " channel transfers"
                     : std::string()) +
                "; the bake file does not match its plug-ins (bake again)");
}

namespace {

// A bake's basis made again from its plug-in record ("key = value" lines, as
// Params::describe writes them) and its saved state: what re-compressing a
// bake file needs, without its scene's mesh or map (a bake may travel alone).
std::shared_ptr<Basis> basis_of_record(const PluginRecord& record, const BasisState& state,
                                       PluginRegistry& registry, const std::string& role) {
  const SourceLocation where{"the bake's " + role + " \"" + record.name + "\""};
  Params params(where);
  const auto trim = [](std::string text) {
    const auto first = text.find_first_not_of(" \t"), last = text.find_last_not_of(" \t");
    return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
  };
  std::istringstream lines(record.parameters);
  for (std::string line; std::getline(lines, line);) {
    const auto equals = line.find('=');
    if (trim(line).empty()) continue;
    if (equals == std::string::npos) throw Error(where, "unreadable parameter \"" + line + "\"");
    parse_assignment(trim(line.substr(0, equals)) + "=" + trim(line.substr(equals + 1)), where,
                     params);
  }
  auto basis = registry.create<Basis>(record.name, params, where);
  basis->load(state);
  return basis;
}

}  // namespace

RenderedMetric rendered_metric(const BakeData& data, PluginRegistry& registry) {
  std::shared_ptr<Basis> basis;
  try {
    basis = basis_of_record(data.basis, data.basis_state, registry, "basis");
  } catch (const Error& e) {  // e.g. a basis written in Python, absent from this process
    log_warning(std::string(e.what()) +
                "; without the bake's basis its transfer is compressed in coefficient space");
    return {};
  }
  check_bake_dimension(data, *basis);
  if (!data.transfer.glossy()) return RenderedMetric(*basis, nullptr);
  const auto exit = basis_of_record(data.exit, data.exit_state, registry, "exit basis");
  if (exit->size() != data.transfer.exit_rows)
    throw Error("the bake's transfer has " + std::to_string(data.transfer.exit_rows) +
                " exit rows, but its exit basis \"" + data.exit.name + "\" has " +
                std::to_string(exit->size()) + " functions");
  return RenderedMetric(*basis, exit.get());
}

Relighting::Relighting(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry)
    : scene_(scene), data_(data) {
  check_bake_matches(data, scene);
  PluginChoice basis = scene.basis;
  basis_ = registry.create<Basis>(basis.name, basis.params, basis.where);
  basis_->load(data.basis_state);
  check_bake_dimension(data, *basis_);
  scene.check_window(*basis_);
  if (BasisMetric metric = basis_metric(*basis_); !metric.identity)
    light_gram_ = std::move(metric.gram);
  if (data.transfer.glossy()) {
    PluginChoice exit = scene.exit;
    exit_ = registry.create<Basis>(exit.name, exit.params, exit.where);
    exit_->load(data.exit_state);
    if (exit_->size() != data.transfer.exit_rows)
      throw Error(exit.where, "the bake's transfer has " + std::to_string(data.transfer.exit_rows) +
                                  " exit rows, but exit basis \"" + exit.name + "\" has " +
                                  std::to_string(exit_->size()) + " functions; bake again");
    frames_ = tangent_frames(data.mesh);
  }
  if (!scene.point_lights.empty() && data.transfer.channel_groups > 1)
    throw Error(scene.material.location(),
                "point lights need one transfer for all colour channels; this material's "
                "channels differ (coloured diffuse/specular with glossy or bounces, or coloured "
                "subsurface): use grey coefficients with point lights");
  set_point_lights(scene.point_lights);
}

void Relighting::set_point_lights(std::vector<PointLight> lights) {
  point_lights_ = std::move(lights);
  if (!point_lights_.empty() && !projector_)
    projector_ = std::make_unique<PointLightProjector>(
        *basis_, static_cast<int>(scene_.lighting.get_int("nearest")));
}

void Relighting::use_brute_force(int cap_samples) {
  projector_ =
      std::make_unique<PointLightProjector>(PointLightProjector::brute_force(*basis_, cap_samples));
}

std::string Relighting::point_light_rule() const {
  return point_lights_.empty() ? "" : projector_->describe();
}

Eigen::MatrixX3f Relighting::point_radiance(const CompressedTransfer& transfer,
                                            const MatrixXfRow* exit_values) const {
  const auto v = static_cast<Eigen::Index>(data_.mesh.vertex_count());
  if (point_lights_.empty()) return Eigen::MatrixX3f::Zero(v, 3);
  Eigen::MatrixX3f radiance =
      point_light_radiance(data_.mesh, transfer, data_.transfer.exit_rows, *projector_,
                           point_lights_, exit_ ? exit_values : nullptr);
  for (int c = 0; c < 3; ++c) radiance.col(c) *= data_.albedo[c];
  return radiance;
}

Eigen::MatrixX3d Relighting::light(const Environment& environment) const {
  return scene_.project_light(environment, *basis_);
}

Eigen::MatrixX3d Relighting::seen_by_transfer(const Eigen::MatrixX3d& light) const {
  if (light_gram_.size() == 0) return light;
  return light_gram_ * light;
}

RelightKernel Relighting::prepare(const CompressedTransfer& transfer) const {
  return RelightKernel(transfer, data_.transfer.exit_rows * data_.transfer.channel_groups);
}

namespace {

// Colour channels from stacked channel transfers: channel c of the exit
// coefficients of block group_of_channel[c], read toward the camera (glossy).
Eigen::MatrixX3f channel_radiance(const RelightKernel& kernel, const Eigen::MatrixX3d& light,
                                  const TransferSignal& layout, const MatrixXfRow* exit_values) {
  const MatrixXfRow e = kernel.exit_coefficients(light);  // v x 3 (G N_r), RGB interleaved
  const int n_r = layout.exit_rows;
  Eigen::MatrixX3f out(e.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), e.rows(), [&](Eigen::Index p) {
    for (int c = 0; c < 3; ++c) {
      const int first = layout.group_of_channel[std::size_t(c)] * n_r;
      float sum = 0;
      for (int r = 0; r < n_r; ++r)
        sum += (exit_values ? (*exit_values)(p, r) : 1.f) * e(p, 3 * (first + r) + c);
      out(p, c) = sum;
    }
  });
  return out;
}

}  // namespace

Relit Relighting::relight(const RelightKernel& kernel, const Eigen::MatrixX3d& light_coefficients,
                          const Camera& camera) const {
  const Eigen::MatrixX3d light = seen_by_transfer(light_coefficients);
  Relit out;
  out.exit_values = exit_values_toward(camera);  // empty for diffuse transfer
  // The renderers' own relight path (RelightKernel), so CPU results are theirs.
  const MatrixXfRow* exit_values = exit_ ? &out.exit_values : nullptr;
  if (data_.transfer.channel_groups > 1) {  // per-channel transfers: summed here
    out.vertex_radiance = channel_radiance(kernel, light, data_.transfer, exit_values);
    out.summed = true;
  } else {
    out.vertex_radiance = kernel.radiance(light, exit_values);
  }
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= data_.albedo[c];
  if (!point_lights_.empty()) {
    out.vertex_radiance += point_radiance(kernel.transfer(), &out.exit_values);
    out.summed = true;
  }
  return out;
}

MatrixXfRow Relighting::exit_values_toward(const Camera& camera) const {
  if (!exit_) return {};
  return exit_values(*exit_, local_view_directions(data_.mesh, frames_, camera.position));
}

RenderInput Relighting::input(const CompressedTransfer& transfer, const Relit& relit,
                              const Eigen::MatrixX3d& light, const Camera& camera) const {
  RenderInput input;
  input.mesh = &data_.mesh;
  input.transfer = &transfer;
  input.light = seen_by_transfer(light);
  input.albedo = data_.albedo;
  input.camera = camera;
  if (exit_) input.exit_values = &relit.exit_values;
  if (relit.summed) {  // point lights or channel transfers: the renderer draws the sums made here
    input.vertex_radiance = &relit.vertex_radiance;
    input.albedo = Eigen::Vector3f::Ones();
  }
  return input;
}

Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times, const RunOptions& options) {
  Stopwatch clock;
  const Relighting relighting(scene, data, registry);
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  times.add("load lighting + plug-ins", clock.seconds());

  clock = Stopwatch();
  const Eigen::MatrixX3d light = relighting.light(environment);
  const Camera camera = scene.make_camera(data.mesh);
  times.add("project light", clock.seconds());
  if (data.transfer.glossy())
    if (const std::string warning =
            under_resolved_light(light, relighting.basis().coefficient_bands());
        !warning.empty())
      options.warn(warning);

  if (!scene.point_lights.empty())
    options.message("point lights (" + std::to_string(scene.point_lights.size()) +
                    "): " + relighting.point_light_rule());
  Rendered out =
      render_relit(relighting, *renderer, data.compressed, light, camera, &environment, &times);
  return out;
}

void check_encoding(const BakeData& data, const CompressedTransfer& transfer,
                    const std::string& what, bool finite) {
  transfer.validate(static_cast<Eigen::Index>(data.mesh.vertex_count()), finite);
  const Eigen::Index columns =
      data.transfer.dimension() > 0 ? data.transfer.dimension() : data.compressed.dimension;
  if (transfer.dimension != columns)
    throw Error(what + ": the encoding has " + std::to_string(transfer.dimension) +
                " coefficients per vertex; this bake's transfer has " + std::to_string(columns));
}

void Relighting::check_inputs(const CompressedTransfer& transfer,
                              const Eigen::MatrixX3d& light) const {
  check_encoding(data_, transfer, "relight");
  if (light.rows() != basis_->size() || !light.allFinite())
    throw Error("relight: the light must be a finite " + std::to_string(basis_->size()) +
                " x 3 array (one row per coefficient of the light basis), not " +
                std::to_string(light.rows()) + " x 3");
}

Rendered render_relit(const Relighting& relighting, Renderer& renderer,
                      const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                      const Camera& camera, const Environment* background, StageTimes* times) {
  Stopwatch clock;
  Rendered out;
  const Relit relit = relighting.relight(transfer, light, camera);
  out.vertex_radiance = relit.vertex_radiance;
  if (times) times->add("relight vertices", clock.seconds());
  clock = Stopwatch();
  RenderInput input = relighting.input(transfer, relit, light, camera);
  input.background = background;
  out.image = renderer.render(input);
  out.statistics = renderer.statistics();
  if (times) times->add("rasterise", clock.seconds());
  return out;
}

namespace {

// The ground truth (albedo 1) of one colour channel's material.
Eigen::MatrixX3f channel_ground_truth(const SceneSpec& scene, const Mesh& mesh,
                                      const Environment& lighting, const Camera& camera,
                                      const RunOptions& options, const ChannelMaterial& material) {
  const int samples = static_cast<int>(scene.ground_truth.get_int("samples"));
  const auto seed = static_cast<std::uint64_t>(scene.ground_truth.get_int("seed"));
  // Glossy: pi rho(light, view) in each vertex's frame replaces albedo 1.
  Reflectance reflectance;
  std::vector<Frame> frames;
  Eigen::MatrixXd views;
  const Brdf& brdf = material.brdf;
  if (brdf.glossy()) {
    frames = tangent_frames(mesh);
    views = local_view_directions(mesh, frames, camera.position);
    reflectance = [&](std::size_t v, const Eigen::Vector3d& light) {
      return M_PI * brdf.evaluate(frames[v] * light, views.row(Eigen::Index(v)).transpose());
    };
  }
  Eigen::MatrixX3f radiance;
  {
    Progress progress("ground truth", double(mesh.vertex_count()), "rays", options.quiet);
    radiance = ground_truth_radiance(mesh, lighting, samples, seed, &progress, reflectance);
  }
  if (const int bounces = static_cast<int>(scene.transport.get_int("bounces")); bounces > 0) {
    if (brdf.glossy()) {  // view-dependent: paths from each vertex
      Progress progress("ground truth glossy bounces", double(mesh.vertex_count()), "rays",
                        options.quiet);
      radiance += ground_truth_glossy_bounces(mesh, lighting, brdf, views, bounces,
                                              material.bounce_albedo, samples, seed, &progress);
    } else {
      Progress progress("ground truth bounces", double(mesh.vertex_count()) * bounces, "rays",
                        options.quiet);
      radiance = ground_truth_bounces(mesh, radiance, bounces, material.bounce_albedo, samples,
                                      seed, &progress);
    }
  }
  if (!scene.point_lights.empty()) {  // direct light only, as traced up to each light
    Progress progress("ground truth point lights", double(mesh.vertex_count()), "", options.quiet);
    radiance +=
        ground_truth_point_lights(mesh, scene.point_lights, samples, seed, reflectance, &progress);
  }
  if (scene.material.get_bool("subsurface")) {
    // The dipole over every pair of vertices, from Monte Carlo irradiance
    // (a glossy material's own radiance is not irradiance: trace it apart).
    Eigen::MatrixX3f irradiance = radiance;
    if (brdf.glossy()) {
      Progress progress("ground truth irradiance", double(mesh.vertex_count()), "rays",
                        options.quiet);
      irradiance = ground_truth_radiance(mesh, lighting, samples, seed, &progress);
      if (!scene.point_lights.empty())
        irradiance += ground_truth_point_lights(mesh, scene.point_lights, samples, seed);
    }
    Stopwatch clock;
    radiance += subsurface_direct(mesh, irradiance, material.subsurface);
    char line[160];
    std::snprintf(line, sizeof line,
                  "ground truth: the dipole summed over all %zu^2 vertex pairs in %.1f s",
                  mesh.vertex_count(), clock.seconds());
    options.message(line);
  }
  return radiance;
}

}  // namespace

Eigen::MatrixX3f ground_truth_vertices(const SceneSpec& scene, const Mesh& mesh,
                                       const Environment& lighting, const Camera& camera,
                                       const RunOptions& options) {
  // One Monte Carlo run per distinct channel material; each channel takes its own.
  const MaterialChannels channels = scene.channels();
  Eigen::MatrixX3f radiance(static_cast<Eigen::Index>(mesh.vertex_count()), 3);
  for (std::size_t g = 0; g < channels.groups.size(); ++g) {
    const Eigen::MatrixX3f truth =
        channel_ground_truth(scene, mesh, lighting, camera, options, channels.groups[g]);
    for (int c = 0; c < 3; ++c)
      if (channels.group_of_channel[std::size_t(c)] == static_cast<int>(g))
        radiance.col(c) = truth.col(c);
  }
  const Eigen::Vector3f albedo = scene.albedo();
  for (int c = 0; c < 3; ++c) radiance.col(c) *= albedo[c];
  return radiance;
}

Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times,
                             const Environment* lighting) {
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  Stopwatch clock;
  Rendered out;
  const Camera camera = scene.make_camera(mesh);
  out.vertex_radiance =
      ground_truth_vertices(scene, mesh, lighting ? *lighting : environment, camera, options);
  times.add(lighting ? "ground truth under the band-limited light" : "ground truth (Monte Carlo)",
            clock.seconds());
  clock = Stopwatch();
  RenderInput input;
  input.mesh = &mesh;
  input.vertex_radiance = &out.vertex_radiance;  // albedo included
  input.camera = camera;
  input.background = &environment;
  out.image = renderer->render(input);
  times.add("rasterise (" + renderer_choice.name + ")", clock.seconds());
  return out;
}

Rendered render_relit(const Relighting& relighting, Renderer& renderer,
                      const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                      const Camera& camera, const Environment* background) {
  Rendered out;
  const Relit relit = relighting.relight(transfer, light, camera);
  out.vertex_radiance = relit.vertex_radiance;
  RenderInput input = relighting.input(transfer, relit, light, camera);
  input.background = background;
  out.image = renderer.render(input);
  out.statistics = renderer.statistics();
  return out;
}

ErrorStats vertex_error(const Eigen::MatrixX3f& approximation, const Eigen::MatrixX3f& reference) {
  if (approximation.rows() != reference.rows()) throw Error("vertex_error: row counts differ");
  const Eigen::Index n = reference.rows();
  ErrorStats stats;
  if (n == 0) return stats;
  std::vector<double> errors(n);
  double reference_energy = 0;
  for (Eigen::Index v = 0; v < n; ++v) {
    errors[v] = (approximation.row(v) - reference.row(v)).cast<double>().norm() / std::sqrt(3.0);
    reference_energy += reference.row(v).cast<double>().squaredNorm() / 3.0;
  }
  double sum = 0;
  for (double e : errors) sum += e * e;
  stats.rms = std::sqrt(sum / n);
  stats.relative_rms = reference_energy > 0 ? stats.rms / std::sqrt(reference_energy / n) : 0;
  std::sort(errors.begin(), errors.end());
  stats.p99 = errors[std::min<Eigen::Index>(n - 1, static_cast<Eigen::Index>(0.99 * n))];
  stats.max = errors.back();
  return stats;
}

}  // namespace prt
