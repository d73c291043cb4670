// prt texels: a texel scene baked at its atlas's texels (at one or more
// resolutions) and at its mesh's vertices, each measured against the Monte
// Carlo ground truth at points spread over the surface (docs/receivers.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <random>

#include "commands.hpp"
#include "prt/bake.hpp"
#include "prt/ground_truth.hpp"
#include "prt/ground_truth_render.hpp"
#include "prt/output_file.hpp"
#include "prt/progress.hpp"
#include "prt/relighting.hpp"
#include "prt/texel_atlas.hpp"
#include "prt/transport.hpp"
#include "reference_options.hpp"

namespace prt::cli {
namespace fs = std::filesystem;

namespace {

// Points spread uniformly by area over a mesh, each with its triangle and
// the barycentric weights of the triangle's corners 1 and 2.
struct SurfacePoints {
  Mesh points;  // positions and interpolated normals
  std::vector<std::uint32_t> triangle;
  std::vector<Eigen::Vector2f> weights;
};

SurfacePoints surface_points(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::vector<double> cumulative;
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    total += 0.5 * (mesh.positions[t[1]].cast<double>() - a)
                       .cross(mesh.positions[t[2]].cast<double>() - a)
                       .norm();
    cumulative.push_back(total);
  }
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  SurfacePoints out;
  for (std::size_t i = 0; i < count; ++i) {
    const auto f = std::uint32_t(std::min<std::size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), uniform(random) * total) -
            cumulative.begin(),
        cumulative.size() - 1));
    float u = float(uniform(random)), v = float(uniform(random));
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const auto& t = mesh.triangles[f];
    out.points.positions.push_back((1 - u - v) * mesh.positions[t[0]] + u * mesh.positions[t[1]] +
                                   v * mesh.positions[t[2]]);
    out.points.normals.push_back(
        ((1 - u - v) * mesh.normals[t[0]] + u * mesh.normals[t[1]] + v * mesh.normals[t[2]])
            .normalized());
    out.triangle.push_back(f);
    out.weights.emplace_back(u, v);
  }
  return out;
}

// What a per-vertex transfer shows at the points: its vertices' radiance
// interpolated across each triangle (as a renderer does).
Eigen::MatrixX3f from_vertices(const Mesh& mesh, const Eigen::MatrixX3f& radiance,
                               const SurfacePoints& s) {
  Eigen::MatrixX3f out(Eigen::Index(s.triangle.size()), 3);
  for (std::size_t i = 0; i < s.triangle.size(); ++i) {
    const auto& t = mesh.triangles[s.triangle[i]];
    const float u = s.weights[i].x(), v = s.weights[i].y();
    out.row(Eigen::Index(i)) =
        (1 - u - v) * radiance.row(t[0]) + u * radiance.row(t[1]) + v * radiance.row(t[2]);
  }
  return out;
}

// What a per-texel transfer shows at the points: its texture looked up at
// their uvs (triangles are in the same order in the mesh with the atlas).
Eigen::MatrixX3f from_texels(const Mesh& mesh, const RadianceTexture& texture,
                             const SurfacePoints& s) {
  Eigen::MatrixX3f out(Eigen::Index(s.triangle.size()), 3);
  for (std::size_t i = 0; i < s.triangle.size(); ++i) {
    const auto& t = mesh.triangles[s.triangle[i]];
    const float u = s.weights[i].x(), v = s.weights[i].y();
    const Eigen::Vector2f uv =
        (1 - u - v) * mesh.uvs[t[0]] + u * mesh.uvs[t[1]] + v * mesh.uvs[t[2]];
    out.row(Eigen::Index(i)) = texture.lookup(uv).transpose();
  }
  return out;
}

struct Baked {
  SceneSpec scene;
  BakeData data;
  double seconds = 0;
  Eigen::MatrixX3f radiance;  // per row, albedo included, clamped at zero
};

// The scene baked in memory (compressed as it says) and relit under its light.
Baked bake_and_relight(const SceneSpec& scene, PluginRegistry& registry,
                       const Environment& environment, bool quiet) {
  Baked b{scene, {}, 0, {}};
  StageTimes times;
  RunOptions options;
  options.quiet = quiet;
  Stopwatch clock;
  b.data = bake(b.scene, registry, options, times);
  b.seconds = clock.seconds();
  const Relighting relighting(b.scene, b.data, registry);
  b.radiance = relighting
                   .relight(b.data.compressed, relighting.light(environment),
                            b.scene.make_camera(b.data.mesh))
                   .vertex_radiance.cwiseMax(0.f);
  return b;
}

struct Row {
  std::string receivers;
  std::size_t rows = 0;
  double bytes = 0, seconds = 0, error = 0, far = 0;
};

Row row_of(const std::string& name, const Baked& b, const Eigen::MatrixX3f& estimate,
           const Eigen::MatrixX3f& truth) {
  return {name,
          b.data.receiver_count(),
          b.data.metrics.at("stored_bytes"),  // the bake's encoding report
          b.seconds,
          vertex_error(estimate, truth).relative_rms,
          far_off(estimate, truth)};
}

// The ground truth at `points` (albedo applied) and its relative noise.
std::pair<Eigen::MatrixX3f, double> truth_at(const SceneSpec& scene, const Mesh& points,
                                             const RayCaster& occluders,
                                             const Environment& environment, bool quiet,
                                             const std::string& label) {
  const int samples = int(keys::ground_truth::samples(scene.ground_truth));
  const auto seed = std::uint64_t(keys::ground_truth::seed(scene.ground_truth));
  const std::vector<std::uint64_t> seeds{seed, seed + 1, seed + 2, seed + 3};
  Progress progress(label, double(points.vertex_count()), "", quiet);
  auto [mean, noise] = mean_and_noise(ground_truth_estimate(
      points, environment, std::max(1, samples / 4), seeds, &progress, nullptr, &occluders));
  progress.finish();
  const Eigen::Vector3f albedo = scene.albedo();
  for (int c = 0; c < 3; ++c) mean.col(c) *= albedo[c];
  return {mean, noise};
}

// Per texel, per vertex and the truth (the ground truth at the texels of an
// atlas 4x finer, looked up as a texture) from the scene's camera.
void write_images(const Baked& texels, const Baked& vertices, const RayCaster& occluders,
                  const Environment& environment, PluginRegistry& registry, bool quiet,
                  const fs::path& folder) {
  const SceneSpec& scene = texels.scene;
  PluginChoice choice = scene.renderer;
  auto renderer = registry.create<Renderer>(choice.name, choice.params, choice.where);
  const float exposure = float(keys::camera::exposure(scene.camera));
  const TexelSamples fine =
      texel_samples(texels.data.mesh, 4 * texels.data.receivers.atlas.width, "the truth's atlas");
  const Eigen::MatrixX3f fine_truth =
      truth_at(scene, fine.points, occluders, environment, quiet, "ground truth of the image")
          .first;
  auto draw = [&](const Mesh& mesh, const Eigen::MatrixX3f& radiance, const TexelAtlas* atlas,
                  const std::string& name) {
    RenderInput input;
    input.mesh = &mesh;
    input.vertex_radiance = &radiance;
    input.texels = atlas;
    input.camera = scene.make_camera(mesh);
    input.background = &environment;
    const fs::path file = folder / (name + ".png");
    write_image(renderer->render(input), file, exposure);
    std::cout << "wrote " << file.string() << "\n";
  };
  draw(texels.data.mesh, texels.radiance, &texels.data.receivers.atlas, "texels");
  draw(vertices.data.mesh, vertices.radiance, nullptr, "vertices");
  draw(texels.data.mesh, fine_truth, &fine.atlas, "truth");
}

void print_table(const std::vector<Row>& rows, std::size_t points, int samples, double noise) {
  std::printf(
      "\n| receivers | rows | stored bytes | bake (s) | relative RMS error | far off |\n"
      "|---|---|---|---|---|---|\n");
  for (const Row& r : rows)
    std::printf("| %s | %zu | %.0f | %.2f | %.4f | %.1f%% |\n", r.receivers.c_str(), r.rows,
                r.bytes, r.seconds, r.error, 100 * r.far);
  std::printf(
      "\nError at %zu points spread by area over the surface, relative to the ground truth's "
      "RMS (%d samples a point; its noise %.4f); far off: a point's error above a quarter of "
      "that RMS.\n",
      points, samples, noise);
}

}  // namespace

int texels(Context& context, const TexelsArgs& args) {
  SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  if (!scene.texels())
    throw Error(scene.file.string() +
                ": prt texels measures a scene with [receivers] kind = \"texels\"; this one "
                "has " +
                keys::receivers::kind(scene.receivers));
  apply_samples(args.reference, scene);
  if (!args.out.empty()) fs::create_directories(args.out);
  std::vector<std::int64_t> resolutions = args.resolutions;
  if (resolutions.empty()) resolutions.push_back(keys::receivers::resolution(scene.receivers));
  const Environment environment = scene.load_environment();

  SceneSpec at_vertices = scene;
  at_vertices.receivers.set(keys::receivers::kind.name(), std::string("vertices"),
                            SourceLocation{"prt texels"});
  const Baked vertices =
      bake_and_relight(at_vertices, context.registry, environment, context.quiet);
  // The vertex bake's mesh: the texel bakes' without the seams' split
  // (same triangles in the same order, same positions and normals).
  const Mesh& surface = vertices.data.mesh;
  const RayCaster occluders(surface);
  const SurfacePoints s =
      surface_points(surface, std::size_t(args.points),
                     std::uint64_t(keys::ground_truth::seed(scene.ground_truth)) ^ 0x7e8e15ULL);
  const auto [truth, noise] =
      truth_at(scene, s.points, occluders, environment, context.quiet, "ground truth");
  std::vector<Row> rows{
      row_of("vertices", vertices, from_vertices(vertices.data.mesh, vertices.radiance, s), truth)};
  for (std::size_t i = 0; i < resolutions.size(); ++i) {
    SceneSpec at_texels = scene;
    at_texels.receivers.set(keys::receivers::resolution.name(), resolutions[i],
                            SourceLocation{"--resolution"});
    const Baked texels = bake_and_relight(at_texels, context.registry, environment, context.quiet);
    const RadianceTexture texture = radiance_texture(texels.data.receivers.atlas, texels.radiance);
    const std::string name =
        "texels " + std::to_string(resolutions[i]) + " x " + std::to_string(resolutions[i]);
    rows.push_back(row_of(name, texels, from_texels(texels.data.mesh, texture, s), truth));
    if (i + 1 == resolutions.size() && !args.out.empty())
      write_images(texels, vertices, occluders, environment, context.registry, context.quiet,
                   args.out);
  }
  print_table(rows, s.triangle.size(), int(keys::ground_truth::samples(scene.ground_truth)), noise);
  return 0;
}

}  // namespace prt::cli
