// Frame cost of rendering compressed transfer, in one run (Sloan 2003 §6):
//
//   bench_view [scene.toml] [frames]     (needs a display: xvfb-run -a bench_view ...)
//
// 1. GPU: frame time of the scene's encoding drawn by the OpenGL renderer
//    (per-vertex weighted sums of per-cluster constants; glossy: per-pixel
//    y(v).e) next to a plain vertex-colour draw of the same mesh and camera:
//    the overhead ratio. Absolute frame rates are printed too (meaningful on a
//    real GPU; under Mesa llvmpipe they are CPU rasterisation).
// 2. CPU: relighting (per-cluster constants + per-vertex weighted sums)
//    next to the memory-bandwidth limit of reading the per-vertex data
//    (weights, cluster indices) and writing e_p once, at the read bandwidth
//    measured in the same run.
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "prt/bake_file.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Read bandwidth: best of five parallel sums over a 512 MB array.
double read_bandwidth() {
  std::vector<float> data(std::size_t(128) << 20, 1.f);
  double best = 1e30;
  for (int r = 0; r < 5; ++r) {
    prt::Stopwatch clock;
    const double sum = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, data.size(), 1 << 16), 0.0,
        [&](const auto& range, double s) {
          float partial = 0;
          for (std::size_t i = range.begin(); i < range.end(); ++i) partial += data[i];
          return s + partial;
        },
        std::plus<>());
    best = std::min(best, clock.seconds());
    if (sum < 0) std::puts("");  // keep the sum alive
  }
  return double(data.size() * sizeof(float)) / best;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const std::string scene_file =
      argc > 1 ? argv[1] : std::string(PRT_SOURCE_DIR) + "/scenes/bunny_glossy.toml";
  const int frames = argc > 2 ? std::stoi(argv[2]) : 20;
  Progress::set_enabled(false);
  try {
    PluginRegistry registry(PluginRegistry::default_directories());
    SceneSpec scene = SceneSpec::load(scene_file, registry);
    const BakeData data = read_bake(scene.bake_path());
    const Relighting relighting(scene, data, registry);
    const Eigen::MatrixX3d light = relighting.light(scene.load_environment());
    Params gl_params;
    gl_params.set("background", false);
    auto renderer = registry.create<Renderer>("opengl", gl_params);
    const Camera camera = scene.make_camera(data.mesh);
    const Relit relit = relighting.relight(data.compressed, light, camera);
    RenderInput prt_input = relighting.input(data.compressed, relit, light, camera);
    RenderInput plain = prt_input;
    plain.exit_values = nullptr;
    plain.albedo = Eigen::Vector3f::Ones();  // vertex_radiance includes the albedo
    plain.vertex_radiance = &relit.vertex_radiance;

    auto time_frames = [&](const RenderInput& input, std::vector<double>* relight = nullptr) {
      renderer->render(input);  // upload and warm up
      std::vector<double> draw;
      for (int f = 0; f < frames; ++f) {
        renderer->render(input);
        const auto stats = renderer->statistics();
        draw.push_back(stats.at("draw_seconds"));
        if (relight) relight->push_back(stats.at("relight_seconds"));
      }
      return median(draw);
    };
    std::vector<double> constants;
    const double prt_frame = time_frames(prt_input, &constants);
    const double plain_frame = time_frames(plain);
    const auto& c = data.compressed;
    std::printf("scene %s: %zu vertices, %zu triangles, %s, %lld clusters, n' = %d, %s %s\n",
                scene_file.c_str(), data.mesh.vertex_count(), data.mesh.triangle_count(),
                data.transfer.kind.c_str(), static_cast<long long>(c.clusters()), c.components,
                "frame",
                (std::to_string(camera.width) + "x" + std::to_string(camera.height)).c_str());
    std::printf("GPU  %-34s %9.3f ms  (%7.1f frames/s)\n", "compressed transfer frame",
                1e3 * prt_frame, 1 / prt_frame);
    std::printf("GPU  %-34s %9.3f ms  (%7.1f frames/s)\n", "plain vertex-colour frame",
                1e3 * plain_frame, 1 / plain_frame);
    std::printf("GPU  overhead ratio %.2f\n", prt_frame / plain_frame);

    // CPU relighting of every vertex against reading its data once.
    const int rows = data.transfer.exit_rows;
    std::vector<double> cpu;
    for (int f = 0; f < frames; ++f) {
      Stopwatch clock;
      const MatrixXfRow e = exit_coefficients(c, light, rows);
      cpu.push_back(clock.seconds());
      if (e.rows() == 0) std::puts("");
    }
    // Read weights and cluster indices, write e_p (3 N_r floats per vertex).
    const double bytes = double(c.weights.size()) * sizeof(float) +
                         double(c.cluster_of_vertex.size()) * sizeof(std::int32_t) +
                         double(c.vertices()) * 3 * rows * sizeof(float);
    const double bandwidth = read_bandwidth();
    const double limit = bytes / bandwidth;
    std::printf("CPU  per-cluster constants (%lld clusters)   %9.3f ms\n",
                static_cast<long long>(c.clusters()), 1e3 * median(constants));
    std::printf("CPU  relight every vertex (constants + sums) %9.3f ms\n", 1e3 * median(cpu));
    std::printf("CPU  moving %.1f MB of per-vertex data at %.1f GB/s: %.3f ms\n", bytes / 1e6,
                bandwidth / 1e9, 1e3 * limit);
    std::printf("CPU  relight / bandwidth limit ratio %.2f\n", median(cpu) / limit);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_view: %s\n", e.what());
    return 1;
  }
}
