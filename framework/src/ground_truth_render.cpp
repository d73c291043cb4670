// The Monte Carlo ground truth as a render (per vertex and as an image), and
// per-vertex error statistics against it.
#include "prt/ground_truth_render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/glossy_interreflection.hpp"
#include "prt/ground_truth.hpp"
#include "prt/interreflection.hpp"
#include "prt/point_lights.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"
#include "prt/subsurface.hpp"

namespace prt {

namespace {

// Glossy: pi rho(light, view) in each vertex's frame replaces albedo 1; the
// frames and the views toward the camera (for the bounces too).
struct GlossyViews {
  std::vector<Frame> frames;
  Eigen::MatrixXd views;
};
GlossyViews glossy_views(const Mesh& mesh, const Camera& camera) {
  GlossyViews out;
  out.frames = tangent_frames(mesh);
  out.views = local_view_directions(mesh, out.frames, camera.position);
  return out;
}
Reflectance glossy_reflectance(const Brdf& brdf, const GlossyViews& glossy) {
  return [&brdf, &glossy](std::size_t v, const Eigen::Vector3d& light) {
    return M_PI *
           brdf.evaluate(glossy.frames[v] * light, glossy.views.row(Eigen::Index(v)).transpose());
  };
}

// One batch's estimate: `samples` per vertex drawn with `seed`; its direct
// light from the map (each channel material's, albedo 1) traced already.
struct Batch {
  int samples = 0;
  std::uint64_t seed = 0;
  std::string label;                            // after each progress bar's name: " (batch 2 of 4)"
  std::vector<const Eigen::MatrixX3f*> direct;  // per channel material
  const GlossyViews* glossy = nullptr;          // where a material is glossy
};

// Every channel material's direct light from the map for every batch, in one
// pass per material: [material][batch].
std::vector<std::vector<Eigen::MatrixX3f>> direct_light(const SceneSpec& scene, const Mesh& mesh,
                                                        const Environment& lighting,
                                                        const RunOptions& options, int samples,
                                                        const std::vector<std::uint64_t>& seeds,
                                                        const GlossyViews* glossy) {
  std::vector<std::vector<Eigen::MatrixX3f>> out;
  for (const ChannelMaterial& material : scene.channels().groups) {
    Reflectance reflectance;
    if (material.brdf.glossy()) reflectance = glossy_reflectance(material.brdf, *glossy);
    const std::string batches =
        seeds.size() == 1 ? std::string() : " (" + std::to_string(seeds.size()) + " batches)";
    Progress progress("ground truth" + batches, double(mesh.vertex_count()), "rays", options.quiet);
    out.push_back(
        ground_truth_estimate(mesh, lighting, samples, seeds, &progress, reflectance).batches);
  }
  return out;
}

// The irradiance the dipole scatters (E / pi): the channel's own Monte Carlo
// radiance, or for a glossy material (whose radiance is not irradiance) a
// trace of its own.
Eigen::MatrixX3f dipole_irradiance(const SceneSpec& scene, const Mesh& mesh,
                                   const Environment& lighting, const RunOptions& options,
                                   const ChannelMaterial& material, const Batch& batch,
                                   const Eigen::MatrixX3f& radiance) {
  if (!material.brdf.glossy()) return radiance;
  Progress progress("ground truth irradiance" + batch.label, double(mesh.vertex_count()), "rays",
                    options.quiet);
  Eigen::MatrixX3f irradiance =
      ground_truth_radiance(mesh, lighting, batch.samples, batch.seed, &progress);
  if (!scene.point_lights.empty())
    irradiance += ground_truth_point_lights(mesh, scene.point_lights, batch.samples, batch.seed);
  return irradiance;
}

// One channel material's estimate: the surface's radiance, and (subsurface
// materials) the irradiance its dipole scatters, applied to every batch at
// once by add_dipole_terms.
struct ChannelEstimate {
  Eigen::MatrixX3f radiance, irradiance;
};

// The ground truth (albedo 1) of one colour channel's material, one batch.
ChannelEstimate channel_ground_truth(const SceneSpec& scene, const Mesh& mesh,
                                     const Environment& lighting, const RunOptions& options,
                                     const ChannelMaterial& material, std::size_t group,
                                     const Batch& batch) {
  const int samples = batch.samples;
  const std::uint64_t seed = batch.seed;
  const Brdf& brdf = material.brdf;
  const Reflectance reflectance =
      brdf.glossy() ? glossy_reflectance(brdf, *batch.glossy) : Reflectance();
  Eigen::MatrixX3f radiance = *batch.direct[group];
  if (const int bounces = static_cast<int>(keys::transport::bounces(scene.transport));
      bounces > 0) {
    if (brdf.glossy()) {  // view-dependent: paths from each vertex
      Progress progress("ground truth glossy bounces" + batch.label, double(mesh.vertex_count()),
                        "rays", options.quiet);
      radiance += ground_truth_glossy_bounces(mesh, lighting, brdf, batch.glossy->views, bounces,
                                              material.bounce_albedo, samples, seed, &progress);
    } else {
      Progress progress("ground truth bounces" + batch.label, double(mesh.vertex_count()) * bounces,
                        "rays", options.quiet);
      radiance = ground_truth_bounces(mesh, radiance, bounces, material.bounce_albedo, samples,
                                      seed, &progress);
    }
  }
  if (!scene.point_lights.empty()) {  // direct light only, as traced up to each light
    Progress progress("ground truth point lights" + batch.label, double(mesh.vertex_count()), "",
                      options.quiet);
    radiance +=
        ground_truth_point_lights(mesh, scene.point_lights, samples, seed, reflectance, &progress);
  }
  if (!keys::material::subsurface(scene.material)) return {radiance, {}};
  Eigen::MatrixX3f irradiance =
      dipole_irradiance(scene, mesh, lighting, options, material, batch, radiance);
  return {std::move(radiance), std::move(irradiance)};
}

// One estimate of the whole scene: its surface radiance (every channel
// material, albedo included) and each material's irradiance for the dipole.
struct SceneEstimate {
  Eigen::MatrixX3f radiance;
  std::vector<Eigen::MatrixX3f> irradiance;  // per channel material; empty without subsurface
};

SceneEstimate scene_estimate(const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
                             const RunOptions& options, const Batch& batch) {
  // One Monte Carlo run per distinct channel material; each channel takes its own.
  const MaterialChannels channels = scene.channels();
  SceneEstimate out;
  out.radiance.resize(static_cast<Eigen::Index>(mesh.vertex_count()), 3);
  for (std::size_t g = 0; g < channels.groups.size(); ++g) {
    ChannelEstimate truth =
        channel_ground_truth(scene, mesh, lighting, options, channels.groups[g], g, batch);
    for (int c = 0; c < 3; ++c)
      if (channels.group_of_channel[std::size_t(c)] == static_cast<int>(g))
        out.radiance.col(c) = truth.radiance.col(c);
    out.irradiance.push_back(std::move(truth.irradiance));
  }
  const Eigen::Vector3f albedo = scene.albedo();
  for (int c = 0; c < 3; ++c) out.radiance.col(c) *= albedo[c];
  return out;
}

// Each subsurface material's dipole over every pair of vertices, for every
// batch in one pass (the pair kernel is the cost), added to each estimate.
void add_dipole_terms(const SceneSpec& scene, const Mesh& mesh, const RunOptions& options,
                      std::vector<SceneEstimate>& estimates) {
  const MaterialChannels channels = scene.channels();
  const Eigen::Vector3f albedo = scene.albedo();
  const auto rows = static_cast<Eigen::Index>(mesh.vertex_count());
  const auto batches = Eigen::Index(estimates.size());
  for (std::size_t g = 0; g < channels.groups.size(); ++g) {
    if (estimates.empty() || estimates[0].irradiance[g].size() == 0) continue;
    Eigen::MatrixXf stacked(rows, 3 * batches);
    for (Eigen::Index b = 0; b < batches; ++b)
      stacked.middleCols(3 * b, 3) = estimates[std::size_t(b)].irradiance[g];
    Stopwatch clock;
    const Eigen::MatrixXf terms =
        subsurface_direct_columns(mesh, stacked, channels.groups[g].subsurface);
    char line[200];
    std::snprintf(line, sizeof line,
                  "ground truth: the dipole summed over all %zu^2 vertex pairs for %lld batches "
                  "in %.1f s",
                  mesh.vertex_count(), static_cast<long long>(batches), clock.seconds());
    options.message(line);
    for (Eigen::Index b = 0; b < batches; ++b)
      for (int c = 0; c < 3; ++c)
        if (channels.group_of_channel[std::size_t(c)] == static_cast<int>(g))
          estimates[std::size_t(b)].radiance.col(c) += albedo[c] * terms.col(3 * b + c);
  }
}

// Independent batches give the error bar of their mean whatever the sampling
// inside each (stratified samples are not independent, so their own spread
// would overstate it); four keep most of the stratification's gain.
constexpr int kReferenceBatches = 4;

// Batch b's seed: far from every other seed's batches (SplitMix64's mix).
std::uint64_t batch_seed(std::uint64_t seed, int batch) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * std::uint64_t(batch + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Everything the reference depends on: a change of any gives another key.
std::string reference_key(const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
                          const Camera& camera, int samples) {
  ReferenceKey key;
  // v3: each stratum's sample picked from a pool drawn once (issue 42).
  key.add("prt reference v3: batches " + std::to_string(kReferenceBatches) + ", sample pools");
  key.add(mesh.positions.data(), mesh.positions.size() * sizeof(mesh.positions[0]));
  key.add(mesh.normals.data(), mesh.normals.size() * sizeof(mesh.normals[0]));
  key.add(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
  key.add(double(lighting.width())), key.add(double(lighting.height()));
  key.add(lighting.pixels().data(), lighting.pixels().size() * sizeof(float));
  key.add(lighting.rotation().data(), 9 * sizeof(double));
  key.add(scene.material.describe());
  key.add(double(keys::transport::bounces(scene.transport)));
  key.add(double(samples));
  key.add(double(keys::ground_truth::seed(scene.ground_truth)));
  for (const PointLight& light : scene.point_lights) {
    key.add(light.position.data(), 3 * sizeof(double));
    key.add(light.colour.data(), 3 * sizeof(double));
    key.add(light.intensity), key.add(light.radius);
  }
  bool glossy = false;  // only a glossy material's radiance depends on the view
  for (const ChannelMaterial& material : scene.channels().groups)
    glossy = glossy || material.brdf.glossy();
  if (glossy) key.add(camera.position.data(), 3 * sizeof(float));
  return key.hex();
}

Reference traced_reference(const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
                           const Camera& camera, const RunOptions& options, int samples) {
  const auto seed = static_cast<std::uint64_t>(keys::ground_truth::seed(scene.ground_truth));
  Reference out;
  out.samples = samples;
  out.batches = std::min(kReferenceBatches, samples);
  const auto rows = static_cast<Eigen::Index>(mesh.vertex_count());
  std::vector<std::uint64_t> seeds;
  for (int b = 0; b < out.batches; ++b) seeds.push_back(batch_seed(seed, b));
  // Frames and views once, for every glossy material and batch.
  std::optional<GlossyViews> glossy;
  for (const ChannelMaterial& material : scene.channels().groups)
    if (material.brdf.glossy() && !glossy) glossy = glossy_views(mesh, camera);
  const GlossyViews* views = glossy ? &*glossy : nullptr;
  const std::vector<std::vector<Eigen::MatrixX3f>> direct =
      direct_light(scene, mesh, lighting, options, samples / out.batches, seeds, views);
  std::vector<SceneEstimate> estimates;
  for (int b = 0; b < out.batches; ++b) {
    const std::string label = out.batches == 1 ? std::string()
                                               : " (batch " + std::to_string(b + 1) + " of " +
                                                     std::to_string(out.batches) + ")";
    Batch batch{samples / out.batches, seeds[std::size_t(b)], label, {}, views};
    for (const auto& material : direct) batch.direct.push_back(&material[std::size_t(b)]);
    estimates.push_back(scene_estimate(scene, mesh, lighting, options, batch));
  }
  add_dipole_terms(scene, mesh, options, estimates);
  Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(rows, 3), squares = sum;
  for (const SceneEstimate& estimate : estimates) {
    const Eigen::MatrixX3d radiance = estimate.radiance.cast<double>();
    sum += radiance;
    squares += radiance.array().square().matrix();
  }
  const double n = out.batches;
  out.radiance = (sum / n).cast<float>();
  // The standard error of the mean of n batches: sqrt(s^2 / n), s^2 the batches' variance.
  if (out.batches > 1)
    out.standard_error = ((squares - sum.array().square().matrix() / n) / (n - 1) / n)
                             .array()
                             .max(0.0)
                             .sqrt()
                             .matrix()
                             .cast<float>();
  else
    out.standard_error = Eigen::MatrixX3f::Zero(rows, 3);
  return out;
}

}  // namespace

Reference reference_radiance(const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
                             const Camera& camera, const RunOptions& options,
                             const ReferenceCache* cache) {
  const int samples = static_cast<int>(keys::ground_truth::samples(scene.ground_truth));
  const std::string key =
      cache ? reference_key(scene, mesh, lighting, camera, samples) : std::string();
  if (cache)
    if (std::optional<Reference> kept = cache->load(key, mesh.vertex_count())) {
      options.message("ground truth: reused " + kept->cached.string() + " (" +
                      std::to_string(samples) +
                      " samples per vertex; prt clears nothing: remove the folder to recompute)");
      return *kept;
    }
  Reference out = traced_reference(scene, mesh, lighting, camera, options, samples);
  if (cache) {
    if (const std::string why = cache->store(key, out); !why.empty())
      options.warn("ground truth: not kept for reuse: " + why);
    else
      options.message("ground truth: kept for reuse in " + cache->file(key).string());
  }
  return out;
}

Eigen::MatrixX3f ground_truth_vertices(const SceneSpec& scene, const Mesh& mesh,
                                       const Environment& lighting, const Camera& camera,
                                       const RunOptions& options) {
  return reference_radiance(scene, mesh, lighting, camera, options).radiance;
}

Image render_reference(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                       const Eigen::MatrixX3f& radiance, const Environment& background) {
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  RenderInput input;
  input.mesh = &mesh;
  input.vertex_radiance = &radiance;  // albedo included
  input.camera = scene.make_camera(mesh);
  input.background = &background;
  return renderer->render(input);
}

Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times,
                             const Environment* lighting, const ReferenceCache* cache) {
  const Environment environment = scene.load_environment();  // the light, and the background
  Stopwatch clock;
  Rendered out;
  out.vertex_radiance = reference_radiance(scene, mesh, lighting ? *lighting : environment,
                                           scene.make_camera(mesh), options, cache)
                            .radiance;
  times.add(lighting ? "ground truth under the band-limited light" : "ground truth (Monte Carlo)",
            clock.seconds());
  clock = Stopwatch();
  out.image = render_reference(scene, mesh, registry, out.vertex_radiance, environment);
  times.add("rasterise (" + scene.renderer.name + ")", clock.seconds());
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

Reference band_limited_truth(const SceneSpec& scene, const Mesh& mesh, const Relighting& relighting,
                             const Environment& environment, const Eigen::MatrixX3d& light,
                             const Camera& camera, const RunOptions& options,
                             const ReferenceCache* cache) {
  return reference_radiance(scene, mesh, environment.band_limited(relighting.basis(), light),
                            camera, options, cache);
}

ErrorBudget error_budget(const Eigen::MatrixX3f& truth, const Eigen::MatrixX3f& band_limited,
                         const Eigen::MatrixX3f& exact, const Eigen::MatrixX3f& compressed) {
  return {vertex_error(band_limited, truth).rms, vertex_error(exact, band_limited).rms,
          vertex_error(compressed, exact).rms, vertex_error(compressed, truth).rms};
}

}  // namespace prt
