#include "prt/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "prt/basis.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"
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

}  // namespace

void record(const CompressionReport& r, std::map<std::string, double>& metrics) {
  metrics["squared_error"] = r.squared_error;
  metrics["vertex_squared_error_p50"] = r.vertex_error_p50;
  metrics["vertex_squared_error_p90"] = r.vertex_error_p90;
  metrics["vertex_squared_error_p99"] = r.vertex_error_p99;
  metrics["vertex_squared_error_max"] = r.vertex_error_max;
  metrics["stored_floats"] = r.stored_floats;
  metrics["stored_bytes"] = r.stored_bytes;
  metrics["encode_seconds"] = r.encode_seconds;
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

  TransportOptions transport;
  transport.shadowed = scene.transport.get_bool("shadowed");
  TransportResult result;
  {
    Progress progress("bake transfer", double(data.mesh.vertex_count()),
                      transport.shadowed ? "rays" : "", options.quiet);
    if (basis->can_fit()) {
      // Trace once keeping the bits, fit the basis to them, then project.
      transport.keep_visibility = true;
      result =
          diffuse_transfer(data.mesh, set, Eigen::MatrixXd(set.size(), 0), transport, &progress);
    } else {
      result = diffuse_transfer(data.mesh, set, *basis, transport, &progress);
    }
  }
  times.add("trace + project", result.trace_seconds);
  if (basis->can_fit()) {
    clock = Stopwatch();
    basis->fit({&data.mesh, &set, &result.visibility});
    times.add("fit basis (" + basis_choice.name + ")", clock.seconds());
    clock = Stopwatch();
    result.transfer = project_visibility(data.mesh, set, result.visibility, *basis);
    times.add("project", clock.seconds());
    result.visibility = VisibilityBits();  // not needed past here
  }

  clock = Stopwatch();
  const int terms = basis->approximation_terms();
  data.compressed = terms > 0 ? keep_largest(result.transfer, terms)
                              : compressor->encode(result.transfer, &data.mesh);
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
  data.basis_state = basis->save();
  data.metrics["rays_cast"] = static_cast<double>(result.rays_cast);
  data.metrics["trace_project_seconds"] = result.trace_seconds;
  data.metrics["encode_seconds"] = encode_seconds;
  data.metrics["squared_error"] =
      squared_error(data.transfer.coefficients, data.compressed.decode());
  data.metrics["stored_floats"] = data.compressed.stored_floats();
  return data;
}

void check_bake_matches(const BakeData& data, const SceneSpec& scene) {
  const std::string wanted = scene.basis.params.describe();
  if (data.basis.name != scene.basis.name || data.basis.parameters != wanted)
    throw Error(scene.basis.where,
                "the bake file was made with basis \"" + data.basis.name + "\" (" +
                    data.basis.parameters.substr(0, data.basis.parameters.find('\n')) +
                    "), but the scene asks for \"" + scene.basis.name + "\" (" +
                    wanted.substr(0, wanted.find('\n')) + "); bake again");
}

Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times) {
  check_bake_matches(data, scene);
  Stopwatch clock;
  PluginChoice basis_choice = scene.basis, renderer_choice = scene.renderer;
  auto basis = registry.create<Basis>(basis_choice.name, basis_choice.params, basis_choice.where);
  basis->load(data.basis_state);
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  times.add("load lighting + plug-ins", clock.seconds());

  clock = Stopwatch();
  RenderInput input;
  input.mesh = &data.mesh;
  input.transfer = &data.compressed;
  input.light = environment.project(*basis);
  input.albedo = data.albedo;
  input.camera = scene.make_camera(data.mesh);
  input.background = &environment;
  times.add("project light", clock.seconds());

  clock = Stopwatch();
  Rendered out;
  out.vertex_radiance = relight(data.compressed, input.light);
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= data.albedo[c];
  times.add("relight vertices", clock.seconds());

  clock = Stopwatch();
  out.image = renderer->render(input);
  times.add("rasterise (" + renderer_choice.name + ")", clock.seconds());
  return out;
}

Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times) {
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  Stopwatch clock;
  Rendered out;
  {
    const int samples = static_cast<int>(scene.ground_truth.get_int("samples"));
    Progress progress("ground truth", double(mesh.vertex_count()), "rays", options.quiet);
    out.vertex_radiance = ground_truth_radiance(
        mesh, environment, samples, static_cast<std::uint64_t>(scene.ground_truth.get_int("seed")),
        &progress);
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
  input.camera = scene.make_camera(mesh);
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
