#include "prt/pipeline.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "prt/basis.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/interreflection.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"
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

namespace {

std::string transport_description(const SceneSpec& scene, const DirectionSet& set) {
  return set.kind + " " + std::to_string(set.size()) + " directions, " +
         (scene.transport.get_bool("shadowed") ? "shadowed" : "unshadowed") +
         ", seed=" + std::to_string(scene.transport.get_int("seed"));
}

// The SH order of the light basis of glossy transfer.
int sh_order_of(const Basis& basis) {
  const int order = static_cast<int>(std::lround(std::sqrt(double(basis.size()))));
  if (order * order != basis.size() || !basis.can_rotate())
    throw Error("glossy transfer needs a rotating SH light basis");
  return order;
}

// The subsurface term is view-independent exit radiance: diffuse transfer
// adds it to the vector; glossy transfer adds it to the constant exit row
// (y_00 = 1 / (2 sqrt(pi)), so a constant c has coefficient 2 sqrt(pi) c).
void add_subsurface(const MatrixXfRow& scattered, TransferSignal& transfer) {
  if (!transfer.exit.glossy()) {
    transfer.coefficients += scattered;
    return;
  }
  transfer.coefficients.leftCols(scattered.cols()) +=
      static_cast<float>(2.0 * std::sqrt(M_PI)) * scattered;
}

// Memory this machine can give now (MemAvailable), in bytes.
double available_memory() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kilobytes = 0;
  while (meminfo >> key >> kilobytes) {
    if (key == "MemAvailable:") return kilobytes * 1024.0;
    meminfo.ignore(256, '\n');
  }
  return double(sysconf(_SC_AVPHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
}

// Refuses, before any ray, a bake whose largest arrays cannot fit: the
// transfer (twice: exact and decoded), kept visibility bits and bounce hits,
// and the basis evaluated at every direction (unless it projects by a fast
// transform).
void require_memory(const SceneSpec& scene, const Mesh& mesh, const DirectionSet& set,
                    const Basis& basis, bool keep_visibility, bool keep_hits) {
  const double v = double(mesh.vertex_count()), d = double(set.size()), n = double(basis.size());
  const double rows = scene.glossy() ? double(scene.exit_basis().rows()) : 1.0;
  const double projection = basis.has_fast_projection(set) ? 0 : d * n * sizeof(double);
  const double bytes = 2 * v * rows * n * sizeof(float) + projection +
                       (keep_visibility ? v * d / 8 : 0) + (keep_hits ? v * d * 8 : 0);
  const double available = available_memory();
  if (bytes > available) {
    char message[400];
    std::snprintf(message, sizeof message,
                  "this bake needs about %.1f GB (%.0f vertices x %.0f coefficients%s, %.0f "
                  "directions), but %.1f GB are available; lower the basis size, rays or mesh "
                  "resolution",
                  bytes / 1e9, v, rows * n, rows > 1 ? " per glossy matrix" : "", d,
                  available / 1e9);
    throw Error(scene.basis.where, message);
  }
}

}  // namespace

void record(const CompressionReport& r, std::map<std::string, double>& metrics) {
  metrics["squared_error"] = r.squared_error;
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

BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times) {
  Stopwatch clock;
  PluginChoice basis_choice = scene.basis, compressor_choice = scene.compressor;
  auto basis = registry.create<Basis>(basis_choice.name, basis_choice.params, basis_choice.where);
  auto compressor = registry.create<Compressor>(compressor_choice.name, compressor_choice.params,
                                                compressor_choice.where);
  times.add("load plug-ins", clock.seconds());
  if (basis->domain() != Domain::sphere)
    throw Error(basis_choice.where,
                "basis \"" + basis_choice.name +
                    "\" is defined over the hemisphere of a local frame (for exit radiance of "
                    "glossy transfer); diffuse transfer is a function over the whole sphere: use "
                    "a sphere basis such as \"sh\"");
  if (scene.glossy() && basis_choice.name != "sh")
    throw Error(basis_choice.where,
                "glossy transfer rotates the light into each vertex's frame and projects it over "
                "the hemisphere in spherical harmonics; use basis \"sh\" (not \"" +
                    basis_choice.name + "\")");
  if (basis->approximation_terms() > 0 && compressor_choice.name != "none")
    throw Error(compressor_choice.where,
                "basis \"" + basis_choice.name +
                    "\" approximates non-linearly (keeps the largest coefficients); it cannot be "
                    "combined with compressor \"" +
                    compressor_choice.name + "\": use \"none\"");

  clock = Stopwatch();
  BakeData data;
  data.mesh = scene.load_mesh();
  times.add("load mesh", clock.seconds());

  clock = Stopwatch();
  const DirectionSet set = scene.directions();
  times.add("directions", clock.seconds());

  const bool glossy = scene.glossy(), subsurface = scene.material.get_bool("subsurface");
  const int bounces = static_cast<int>(scene.transport.get_int("bounces"));
  TransportOptions transport;
  transport.shadowed = scene.transport.get_bool("shadowed");
  transport.keep_hits = bounces > 0;
  // Bases fitted to the visibility and glossy matrices need the bits kept;
  // everything else projects while tracing.
  transport.keep_visibility = basis->can_fit() || glossy;
  require_memory(scene, data.mesh, set, *basis, transport.keep_visibility || options.traced,
                 transport.keep_hits);
  TransportResult result;
  if (options.traced) {  // a sweep traced these rays once for many configurations
    transport.keep_visibility = true;
    result.visibility = options.traced->visibility;
    result.hits = options.traced->hits;
    if (result.visibility.vertices() != data.mesh.vertex_count() ||
        result.visibility.directions() != static_cast<std::size_t>(set.size()) ||
        (transport.keep_hits && result.hits.size() != data.mesh.vertex_count()))
      throw Error("bake: the traced visibility does not match the scene's mesh and directions");
  } else {
    Progress progress("bake transfer", double(data.mesh.vertex_count()),
                      transport.shadowed ? "rays" : "", options.quiet);
    result =
        transport.keep_visibility
            ? diffuse_transfer(data.mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress)
            : diffuse_transfer(data.mesh, set, *basis, transport, &progress);
  }
  times.add(transport.keep_visibility ? "trace" : "trace + project", result.trace_seconds);
  if (basis->can_fit()) {
    clock = Stopwatch();
    basis->fit({&data.mesh, &set, &result.visibility});
    times.add("fit basis (" + basis_choice.name + ")", clock.seconds());
  }
  if (transport.keep_visibility && (!glossy || subsurface)) {
    clock = Stopwatch();
    result.transfer = project_visibility(data.mesh, set, result.visibility, *basis);
    times.add("project", clock.seconds());
  }
  if (bounces > 0) {
    clock = Stopwatch();
    Progress progress("inter-reflection", bounces, "", options.quiet);
    Interreflection light = interreflect(data.mesh, set, result.hits, result.transfer.coefficients,
                                         bounces, scene.bounce_albedo(), &progress);
    // How much the bounces add per vertex (transfer norm with / without - 1):
    // near zero on convex parts, large in concave ones.
    std::vector<double> gain(static_cast<std::size_t>(light.total.rows()));
    for (Eigen::Index p = 0; p < light.total.rows(); ++p)
      gain[p] =
          light.total.row(p).norm() / std::max(1e-30f, result.transfer.coefficients.row(p).norm()) -
          1.0;
    std::sort(gain.begin(), gain.end());
    for (const auto& [name, q] : {std::pair{"p50", 0.5}, {"p90", 0.9}, {"p99", 0.99}})
      data.metrics[std::string("bounce_gain_") + name] = gain[std::size_t(q * (gain.size() - 1))];
    data.metrics["bounce_gain_max"] = gain.empty() ? 0.0 : gain.back();
    if (!options.quiet)
      std::printf(
          "inter-reflection: transfer gain per vertex median %.1f%%, 90th %.1f%%, "
          "99th %.1f%%, max %.1f%%\n",
          100 * data.metrics["bounce_gain_p50"], 100 * data.metrics["bounce_gain_p90"],
          100 * data.metrics["bounce_gain_p99"], 100 * data.metrics["bounce_gain_max"]);
    result.transfer.coefficients = std::move(light.total);
    for (std::size_t b = 0; b < light.bounce_norms.size(); ++b)
      data.metrics["bounce_" + std::to_string(b + 1) + "_norm"] = light.bounce_norms[b];
    result.hits = HitLists();
    times.add("inter-reflection (" + std::to_string(bounces) + " bounces)", clock.seconds());
  }
  MatrixXfRow scattered;
  if (subsurface) {
    clock = Stopwatch();
    scattered = subsurface_transfer(data.mesh, result.transfer.coefficients, scene.subsurface());
    times.add("subsurface (hierarchical diffusion)", clock.seconds());
  }
  if (glossy) {
    clock = Stopwatch();
    const GlossyChain chain =
        GlossyChain::make(scene.brdf(), scene.exit_basis(), sh_order_of(*basis),
                          scene.material.get_string("projection") == "least-squares",
                          scene.material.get_real("cutoff"));
    times.add("BRDF matrix", clock.seconds());
    clock = Stopwatch();
    Progress progress("glossy matrices", double(data.mesh.vertex_count()), "", options.quiet);
    result.transfer = glossy_transfer(data.mesh, set, result.visibility, *basis, chain, &progress);
    times.add("glossy matrices (" + std::to_string(chain.exit.rows()) + "x" +
                  std::to_string(basis->size()) + ")",
              clock.seconds());
  }
  if (subsurface) add_subsurface(scattered, result.transfer);
  result.visibility = VisibilityBits();  // not needed past here

  clock = Stopwatch();
  const int terms = basis->approximation_terms();
  try {
    data.compressed = terms > 0 ? keep_largest(result.transfer, terms)
                                : compressor->encode(result.transfer, &data.mesh);
  } catch (const std::bad_alloc&) {  // the compressor's own memory is not estimated up front
    throw Error(compressor_choice.where, "out of memory while compressing the " +
                                             std::to_string(result.transfer.vertices()) + " x " +
                                             std::to_string(result.transfer.dimension()) +
                                             " transfer with compressor \"" +
                                             compressor_choice.name + "\"");
  }
  const double encode_seconds = clock.seconds();
  times.add("compress (" + compressor_choice.name + ")", encode_seconds);
  const CompressionReport report =
      measure(result.transfer, data.compressed, &data.mesh, encode_seconds);
  record(report, data.metrics);
  if (!options.quiet) std::printf("%s", report.text().c_str());

  data.transfer = std::move(result.transfer);
  data.scene_file = scene.file.string();
  data.scene_text = scene.text;
  data.transport = transport_description(scene, set);
  const auto& basis_info = registry.find(PluginKind::basis, basis_choice.name);
  const auto& compressor_info = registry.find(PluginKind::compressor, compressor_choice.name);
  data.basis = {basis_choice.name, basis_info.info.version, basis_choice.params.describe()};
  data.compressor = {compressor_choice.name, compressor_info.info.version,
                     compressor_choice.params.describe()};
  data.albedo = scene.albedo();
  data.material = scene.material_description();
  data.bounces = bounces;
  data.subsurface = subsurface;
  data.basis_state = basis->save();
  data.metrics["rays_cast"] = static_cast<double>(result.rays_cast);
  data.metrics["squared_error"] =
      squared_error(data.transfer.coefficients, data.compressed.decode());
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

void check_bake_matches(const BakeData& data, const SceneSpec& scene) {
  const std::string material = scene.material_description();
  const int bounces = static_cast<int>(scene.transport.get_int("bounces"));
  if (data.material != material || data.bounces != bounces ||
      data.subsurface != scene.material.get_bool("subsurface") ||
      data.transfer.exit.kept != scene.exit_basis().kept)
    throw Error(scene.material.location(),
                "the bake file was made for material \"" + data.material + "\" with " +
                    std::to_string(data.bounces) + " bounces" +
                    (data.subsurface ? " and subsurface" : "") + ", but the scene asks for \"" +
                    material + "\" with " + std::to_string(bounces) +
                    " bounces (or another exit basis); bake again");
  const std::string wanted = scene.basis.params.describe();
  if (data.basis.name != scene.basis.name || data.basis.parameters != wanted)
    throw Error(scene.basis.where,
                "the bake file was made with basis \"" + data.basis.name + "\" (" +
                    data.basis.parameters.substr(0, data.basis.parameters.find('\n')) +
                    "), but the scene asks for \"" + scene.basis.name + "\" (" +
                    wanted.substr(0, wanted.find('\n')) + "); bake again");
}

void check_bake_dimension(const BakeData& data, const Basis& basis) {
  const Eigen::Index expected = Eigen::Index(basis.size()) * data.transfer.exit.rows();
  if (data.transfer.dimension() != expected)
    throw Error(data.scene_file + ": the bake's transfer has " +
                std::to_string(data.transfer.dimension()) + " columns, but basis \"" +
                data.basis.name + "\" has " + std::to_string(basis.size()) + " coefficients" +
                (data.transfer.exit.glossy()
                     ? " x " + std::to_string(data.transfer.exit.rows()) + " exit rows"
                     : std::string()) +
                "; the bake file does not match its plug-ins (bake again)");
}

Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times) {
  check_bake_matches(data, scene);
  Stopwatch clock;
  PluginChoice basis_choice = scene.basis, renderer_choice = scene.renderer;
  auto basis = registry.create<Basis>(basis_choice.name, basis_choice.params, basis_choice.where);
  basis->load(data.basis_state);
  check_bake_dimension(data, *basis);
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  times.add("load lighting + plug-ins", clock.seconds());

  clock = Stopwatch();
  const Eigen::MatrixX3d light = scene.project_light(environment, *basis);
  const Camera camera = scene.make_camera(data.mesh);
  times.add("project light", clock.seconds());

  clock = Stopwatch();
  Rendered out;
  const Relit relit = relight_view(data, data.compressed, light, camera);
  out.vertex_radiance = relit.vertex_radiance;
  times.add("relight vertices", clock.seconds());

  clock = Stopwatch();
  RenderInput input = render_input(data, data.compressed, relit, light, camera);
  input.background = &environment;
  out.image = renderer->render(input);
  out.statistics = renderer->statistics();
  times.add("rasterise (" + renderer_choice.name + ")", clock.seconds());
  return out;
}

Relit relight_view(const BakeData& data, const CompressedTransfer& transfer,
                   const Eigen::MatrixX3d& light, const Camera& camera,
                   const std::vector<Frame>* frames) {
  Relit out;
  const ExitBasis& exit = data.transfer.exit;
  out.exit_coefficients = exit_coefficients(transfer, light, exit.rows());
  if (exit.glossy()) {
    out.frames = frames ? *frames : tangent_frames(data.mesh);
    out.vertex_radiance = evaluate_exit(
        out.exit_coefficients, exit, local_view_directions(data.mesh, out.frames, camera.position));
  } else {
    out.vertex_radiance = out.exit_coefficients;
  }
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= data.albedo[c];
  return out;
}

RenderInput render_input(const BakeData& data, const CompressedTransfer& transfer,
                         const Relit& relit, const Eigen::MatrixX3d& light, const Camera& camera) {
  RenderInput input;
  input.mesh = &data.mesh;
  input.transfer = &transfer;
  input.light = light;
  input.albedo = data.albedo;
  input.camera = camera;
  if (data.transfer.exit.glossy()) {
    input.exit_coefficients = &relit.exit_coefficients;
    input.exit_basis = &data.transfer.exit;
    input.frames = &relit.frames;
  }
  return input;
}

Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times) {
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  Stopwatch clock;
  Rendered out;
  const int samples = static_cast<int>(scene.ground_truth.get_int("samples"));
  const auto seed = static_cast<std::uint64_t>(scene.ground_truth.get_int("seed"));
  const Camera camera = scene.make_camera(mesh);
  {
    // Glossy: pi rho(light, view) in each vertex's frame replaces albedo 1.
    Reflectance reflectance;
    std::vector<Frame> frames;
    std::vector<Eigen::Vector3d> views;
    const Brdf brdf = scene.brdf();
    if (brdf.glossy()) {
      frames = tangent_frames(mesh);
      views = local_view_directions(mesh, frames, camera.position);
      reflectance = [&](std::size_t v, const Eigen::Vector3d& light) {
        return M_PI * brdf.evaluate(frames[v] * light, views[v]);
      };
    }
    Progress progress("ground truth", double(mesh.vertex_count()), "rays", options.quiet);
    out.vertex_radiance =
        ground_truth_radiance(mesh, environment, samples, seed, &progress, reflectance);
  }
  if (const int bounces = static_cast<int>(scene.transport.get_int("bounces")); bounces > 0) {
    Progress progress("ground truth bounces", double(mesh.vertex_count()) * bounces, "rays",
                      options.quiet);
    out.vertex_radiance = ground_truth_bounces(mesh, out.vertex_radiance, bounces,
                                               scene.bounce_albedo(), samples, seed, &progress);
  }
  const Eigen::Vector3f albedo = scene.albedo();
  times.add("ground truth (Monte Carlo)", clock.seconds());
  clock = Stopwatch();
  RenderInput input;
  input.mesh = &mesh;
  const Eigen::MatrixX3f unit_albedo = out.vertex_radiance;
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= albedo[c];
  input.vertex_radiance = &unit_albedo;
  input.albedo = albedo;
  input.camera = camera;
  input.background = &environment;
  out.image = renderer->render(input);
  times.add("rasterise (" + renderer_choice.name + ")", clock.seconds());
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
