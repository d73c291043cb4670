// The Monte Carlo ground truth as a render (per vertex and as an image), and
// per-vertex error statistics against it.
#include "prt/ground_truth_render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/glossy_interreflection.hpp"
#include "prt/ground_truth.hpp"
#include "prt/interreflection.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"

namespace prt {

namespace {

// The ground truth (albedo 1) of one colour channel's material.
Eigen::MatrixX3f channel_ground_truth(const SceneSpec& scene, const Mesh& mesh,
                                      const Environment& lighting, const Camera& camera,
                                      const RunOptions& options, const ChannelMaterial& material) {
  const int samples = static_cast<int>(keys::ground_truth::samples(scene.ground_truth));
  const auto seed = static_cast<std::uint64_t>(keys::ground_truth::seed(scene.ground_truth));
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
  if (const int bounces = static_cast<int>(keys::transport::bounces(scene.transport));
      bounces > 0) {
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
  if (keys::material::subsurface(scene.material)) {
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

Eigen::MatrixX3f band_limited_truth(const SceneSpec& scene, const Mesh& mesh,
                                    const Relighting& relighting, const Environment& environment,
                                    const Eigen::MatrixX3d& light, const Camera& camera,
                                    const RunOptions& options) {
  return ground_truth_vertices(scene, mesh, environment.band_limited(relighting.basis(), light),
                               camera, options);
}

ErrorBudget error_budget(const Eigen::MatrixX3f& truth, const Eigen::MatrixX3f& band_limited,
                         const Eigen::MatrixX3f& exact, const Eigen::MatrixX3f& compressed) {
  return {vertex_error(band_limited, truth).rms, vertex_error(exact, band_limited).rms,
          vertex_error(compressed, exact).rms, vertex_error(compressed, truth).rms};
}

}  // namespace prt
