#include "prt/probe_render.hpp"

#include "prt/bake_checks.hpp"
#include "prt/mesh_compose.hpp"
#include "prt/probe_transfer.hpp"
#include "prt/progress.hpp"

namespace prt {

namespace {

// The lobes' quadrature: the clamped cosine is smooth, and 2,048 Fibonacci
// directions hold its projection to ~1e-4 through SH order 8.
constexpr int kLobeDirections = 2048;

}  // namespace

ProbeRelighting::ProbeRelighting(const SceneSpec& scene, const BakeData& data,
                                 PluginRegistry& registry)
    : scene_(scene), data_(data), lobe_rule_(DirectionSet::fibonacci(kLobeDirections)) {
  if (!data.receivers.probes())
    throw Error(scene.receivers.location(), "the bake file holds transfer at vertices, not probes");
  check_bake_matches(data, scene);
  PluginChoice basis = scene.basis;  // the registry marks the parameters it reads
  basis_ = registry.create<Basis>(basis.name, basis.params, basis.where);
  basis_->load(data.basis_state);
  check_bake_dimension(data, *basis_);
  if (!scene.exit.name.empty()) {
    PluginChoice exit = scene.exit;
    incident_ = registry.create<Basis>(exit.name, exit.params, exit.where);
    incident_->load(data.exit_state);
  } else {
    incident_ = basis_;
  }
  if (incident_->size() != data.transfer.exit_rows)
    throw Error(scene.receivers.location(),
                "the bake's probes hold " + std::to_string(data.transfer.exit_rows) +
                    " incident coefficients, but the scene's incident basis has " +
                    std::to_string(incident_->size()) + "; bake again");
  scene.check_window(*basis_);
  caster_ = std::make_unique<RayCaster>(data.mesh);
  lookup_.interpolation = keys::receivers::interpolation(scene.receivers) == "trilinear"
                              ? ProbeInterpolation::trilinear
                              : ProbeInterpolation::visibility;
  lookup_.normal_bias = float(keys::receivers::normal_bias(scene.receivers));
}

Eigen::MatrixX3d ProbeRelighting::light(const Environment& environment) const {
  // Probes hold primal coefficients of the incident light (least squares),
  // so the light enters as projected, whatever the basis's metric.
  return scene_.project_light(environment, *basis_);
}

std::vector<Eigen::MatrixX3d> ProbeRelighting::incident(const CompressedTransfer& transfer,
                                                        const Eigen::MatrixX3d& light) const {
  return incident_light(transfer, incident_->size(), light);
}

ProbeShading ProbeRelighting::shade(const Mesh& points,
                                    const std::vector<Eigen::MatrixX3d>& incident,
                                    const ProbeLookup& lookup) const {
  return shade_from_probes(points, data_.receivers.grid, data_.receivers.valid, incident,
                           lobes(points), caster_.get(), lookup);
}

Eigen::MatrixXd ProbeRelighting::lobes(const Mesh& points) const {
  return cosine_lobes(*incident_, points.normals, lobe_rule_);
}

ProbeWeights ProbeRelighting::weights(const Mesh& points, const ProbeLookup& lookup) const {
  return probe_weights(points, data_.receivers.grid, data_.receivers.valid, caster_.get(), lookup);
}

Mesh probe_scene_display(const SceneSpec& scene, const BakeData& data) {
  Mesh display = data.mesh;
  if (scene.has_moving()) append(display, scene.load_moving());
  return display;
}

Rendered render_probes(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                       StageTimes& times, const RunOptions& options) {
  Stopwatch clock;
  const ProbeRelighting relighting(scene, data, registry);
  PluginChoice choice = scene.renderer;
  auto renderer = registry.create<Renderer>(choice.name, choice.params, choice.where);
  const Environment environment = scene.load_environment();
  const Mesh display = probe_scene_display(scene, data);
  times.add("load lighting + plug-ins + moving object", clock.seconds());
  clock = Stopwatch();
  const Eigen::MatrixX3d light = relighting.light(environment);
  times.add("project light", clock.seconds());
  clock = Stopwatch();
  const std::vector<Eigen::MatrixX3d> incident = relighting.incident(data.compressed, light);
  times.add("relight probes", clock.seconds());
  clock = Stopwatch();
  const ProbeShading shading = relighting.shade(display, incident, relighting.lookup());
  times.add("shade vertices from probes", clock.seconds());
  if (shading.no_valid_probe > 0)  // usually faces hidden inside geometry, where all probes are
    options.message(std::to_string(shading.no_valid_probe) + " of " +
                    std::to_string(display.vertex_count()) +
                    " vertices have only invalid probes (inside geometry) around them and are "
                    "drawn black; where they show, lower [receivers] spacing");
  Rendered out;
  out.vertex_radiance = shading.radiance;
  const Eigen::Vector3f albedo = scene.albedo();
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= albedo[c];
  clock = Stopwatch();
  RenderInput input;
  input.mesh = &display;
  input.vertex_radiance = &out.vertex_radiance;
  input.camera = scene.make_camera(display);
  input.background = &environment;
  out.image = renderer->render(input);
  out.statistics = renderer->statistics();
  out.statistics["probe_rays"] = double(shading.rays_cast);
  out.statistics["points_without_visible_probe"] = double(shading.unseen);
  times.add("rasterise", clock.seconds());
  return out;
}

}  // namespace prt
