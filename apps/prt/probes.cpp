// prt probes: a probe scene's moving object at several positions, shaded
// from the probes with and without the leak control, against the Monte
// Carlo ground truth that shades it directly (docs/receivers.md).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "prt/bake_checks.hpp"
#include "prt/ground_truth.hpp"
#include "prt/ground_truth_render.hpp"
#include "prt/mesh_compose.hpp"
#include "prt/output_file.hpp"
#include "prt/probe_render.hpp"
#include "prt/progress.hpp"
#include "reference_options.hpp"

namespace prt::cli {
namespace fs = std::filesystem;

namespace {

Eigen::Vector3f parse_position(const std::string& text) {
  std::istringstream in(text);
  Eigen::Vector3f p;
  char comma1 = 0, comma2 = 0;
  in >> p.x() >> comma1 >> p.y() >> comma2 >> p.z();
  if (!in || comma1 != ',' || comma2 != ',' || !p.allFinite() || in.peek() != EOF)
    throw Error("--at \"" + text + "\": give a position as x,y,z (e.g. --at 1.5,0,0.2)");
  return p;
}

// One position's errors: against the truth (the object shadows itself, as
// in the world) and against the light the scene alone lets through (what
// probes can hold: they do not know the object).
struct Row {
  Eigen::Vector3f at;
  double control = 0, trilinear = 0, scene_control = 0, scene_trilinear = 0;
  double far_control = 0, far_trilinear = 0, floor = 0;
};

void write_images(const SceneSpec& scene, PluginRegistry& registry, const Mesh& display,
                  const Eigen::Vector3f& target, float size, const Environment& environment,
                  const std::vector<std::pair<std::string, Eigen::MatrixX3f>>& radiances,
                  const fs::path& stem) {
  PluginChoice choice = scene.renderer;
  auto renderer = registry.create<Renderer>(choice.name, choice.params, choice.where);
  RenderInput input;
  input.mesh = &display;
  // Close to the object, from the room's side of it, a little above.
  input.camera = scene.make_camera(display);
  const Eigen::Vector3f middle = (display.bounds_min() + display.bounds_max()) / 2;
  Eigen::Vector3f away(middle.x() - target.x(), 0, middle.z() - target.z());
  away = away.norm() > 1e-3f ? Eigen::Vector3f(away.normalized()) : Eigen::Vector3f::UnitZ();
  input.camera.target = target;
  input.camera.position = target + size * (2.2f * away + Eigen::Vector3f(0, 1.2f, 0));
  input.camera.fov_degrees = 50;
  input.background = &environment;
  const Eigen::Vector3f albedo = scene.albedo();
  for (const auto& [name, radiance] : radiances) {
    Eigen::MatrixX3f shaded = radiance;
    for (int c = 0; c < 3; ++c) shaded.col(c) *= albedo[c];
    input.vertex_radiance = &shaded;
    const fs::path file = stem.string() + "." + name + ".png";
    write_image(renderer->render(input), file, float(keys::camera::exposure(scene.camera)));
    std::cout << "wrote " << file.string() << "\n";
  }
}

// What every position's measurement shares: the bake, its light at every
// probe, the two lookups and the truth's samples.
struct Measurement {
  const SceneSpec& scene;
  const BakeData& data;
  PluginRegistry& registry;
  const ProbeRelighting& relighting;
  const Environment& environment;
  std::vector<Eigen::MatrixX3d> incident;
  ProbeLookup control, plain;
  int samples = 0;
  std::vector<std::uint64_t> seeds;
  bool quiet = false;
  double shade_seconds = 0;

  std::pair<Eigen::MatrixX3f, double> truth_of(const Mesh& points, const RayCaster& occluders,
                                               const std::string& label) const {
    Progress progress(label, double(points.vertex_count()), "", quiet);
    GroundTruthEstimate truth =
        ground_truth_estimate(points, environment, std::max(1, samples / int(seeds.size())), seeds,
                              &progress, nullptr, &occluders);
    progress.finish();
    return mean_and_noise(truth);
  }

  // The object at `at`: its errors, and (with `out`) the images.
  Row measure(const Eigen::Vector3f& at, const RayCaster& scene_rays, const std::string& where,
              const fs::path& out) {
    Row row;
    row.at = at;
    const Mesh moving = scene.load_moving(at);
    Mesh display = data.mesh;
    append(display, moving);
    const RayCaster display_rays(display);
    Stopwatch clock;
    const ProbeShading with = relighting.shade(moving, incident, control);
    shade_seconds += clock.seconds();
    const ProbeShading without = relighting.shade(moving, incident, plain);
    const auto [truth, noise] = truth_of(moving, display_rays, "ground truth" + where);
    const auto [scene_truth, scene_noise] =
        truth_of(moving, scene_rays, "ground truth without the object's own shadow" + where);
    row.control = vertex_error(with.radiance, truth).relative_rms;
    row.trilinear = vertex_error(without.radiance, truth).relative_rms;
    row.scene_control = vertex_error(with.radiance, scene_truth).relative_rms;
    row.scene_trilinear = vertex_error(without.radiance, scene_truth).relative_rms;
    row.floor = std::max(noise, scene_noise);
    row.far_control = far_off(with.radiance, truth);
    row.far_trilinear = far_off(without.radiance, truth);
    if (!out.empty()) {  // every displayed vertex, for the images
      const auto whole_truth = truth_of(display, display_rays, "ground truth of the image" + where);
      write_images(scene, registry, display, (moving.bounds_min() + moving.bounds_max()) / 2,
                   (moving.bounds_max() - moving.bounds_min()).maxCoeff(), environment,
                   {{"leak_control", relighting.shade(display, incident, control).radiance},
                    {"trilinear", relighting.shade(display, incident, plain).radiance},
                    {"truth", whole_truth.first}},
                   out);
    }
    return row;
  }
};

void print_report(const BakeData& data, const std::vector<Row>& rows, double relight_seconds,
                  double shade_seconds, std::size_t object_vertices, int samples) {
  const ProbeGrid& grid = data.receivers.grid;
  std::printf(
      "probe transfer: %zu probes (%d x %d x %d, spacing %g), %zu inside geometry; "
      "basis %s, %.0f floats stored\n",
      data.receiver_count(), grid.counts[0], grid.counts[1], grid.counts[2], double(grid.spacing),
      std::size_t(std::count(data.receivers.valid.begin(), data.receivers.valid.end(), 0)),
      one_line(data.basis).c_str(), data.compressed.stored_floats());
  std::printf("relight probes: %.3f ms; shade the object with leak control: %.1f ms a position\n",
              1e3 * relight_seconds, 1e3 * shade_seconds / double(rows.size()));
  std::printf(
      "\n| moving object at | leak control | trilinear | trilinear / leak control | without the "
      "object's own shadow: leak control | trilinear | trilinear / leak control | far off "
      "(leak control / trilinear) | ground-truth noise |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& row : rows)
    std::printf(
        "| %g, %g, %g | %.4f | %.4f | %.2fx | %.4f | %.4f | %.2fx | %.1f%% / %.1f%% | "
        "%.4f |\n",
        double(row.at.x()), double(row.at.y()), double(row.at.z()), row.control, row.trilinear,
        row.trilinear / std::max(row.control, 1e-30), row.scene_control, row.scene_trilinear,
        row.scene_trilinear / std::max(row.scene_control, 1e-30), 100 * row.far_control,
        100 * row.far_trilinear, row.floor);
  std::printf(
      "\nRMS error of the object's %zu vertices relative to the ground truth's RMS "
      "(%d samples a vertex); far off: a vertex's error above a quarter of that RMS.\n",
      object_vertices, samples);
}

}  // namespace

int probes(Context& context, const ProbesArgs& args) {
  SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  if (!scene.probes() || !scene.has_moving())
    throw Error(scene.file.string() +
                ": prt probes measures the [moving] object of a scene with [receivers] kind = "
                "\"probes\"; this scene has " +
                (scene.probes() ? "no [moving] section" : "no probes"));
  apply_samples(args.reference, scene);
  std::vector<Eigen::Vector3f> positions;
  for (const std::string& text : args.at) positions.push_back(parse_position(text));
  if (positions.empty())
    positions.push_back(Eigen::Vector3d(keys::place::position(scene.moving).data()).cast<float>());
  if (!args.out.empty()) fs::create_directories(args.out);

  const fs::path bake_file = args.bake.empty() ? scene.bake_path() : fs::path(args.bake);
  const BakeData data = read_bake(bake_file);
  check_bake_records(bake_file.string(), data, context.registry);
  const ProbeRelighting relighting(scene, data, context.registry);
  const Environment environment = scene.load_environment();
  Measurement measurement{scene, data, context.registry, relighting, environment};
  Stopwatch clock;
  measurement.incident = relighting.incident(data.compressed, relighting.light(environment));
  const double relight_seconds = clock.seconds();
  measurement.control = measurement.plain = relighting.lookup();
  measurement.control.interpolation = ProbeInterpolation::visibility;
  measurement.plain.interpolation = ProbeInterpolation::trilinear;
  measurement.samples = int(keys::ground_truth::samples(scene.ground_truth));
  const auto seed = std::uint64_t(keys::ground_truth::seed(scene.ground_truth));
  for (std::uint64_t b = 0; b < 4; ++b)  // as prt render --compare: their spread is the noise
    measurement.seeds.push_back(seed + b);
  measurement.quiet = context.quiet;
  const RayCaster scene_rays(data.mesh);
  std::vector<Row> rows;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const std::string name = "position" + std::to_string(i + 1);
    rows.push_back(measurement.measure(positions[i], scene_rays, " at " + name,
                                       args.out.empty() ? fs::path() : fs::path(args.out) / name));
  }
  print_report(data, rows, relight_seconds, measurement.shade_seconds,
               scene.load_moving().vertex_count(), measurement.samples);
  return 0;
}

}  // namespace prt::cli
