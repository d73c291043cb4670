// Frame cost of rendering compressed transfer, in one run (Sloan 2003 §6):
//
//   bench_view [scene.toml] [frames]     (needs a display: xvfb-run -a bench_view ...)
//
// 1. GPU: frame time of the scene's encoding drawn by the OpenGL renderer
//    (per-vertex weighted sums of per-cluster constants; glossy: per-pixel
//    y(v).e) next to a plain vertex-colour draw of the same mesh and camera:
//    the overhead ratio. Absolute frame rates are printed too (meaningful on a
//    real GPU; under Mesa llvmpipe they are CPU rasterisation).
// 2. CPU: relighting (per-cluster constants + per-vertex weighted sums, and
//    for glossy the dot with the exit basis toward the camera) next to the
//    time of streaming the same per-vertex bytes (weights, cluster indices,
//    exit values; three floats written per vertex) on every core in the same
//    run: the bound a relight cannot beat.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "prt/bake_file.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/relight.hpp"
#include "prt/renderer.hpp"
#include "prt/view_transfer.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {

using prt::bench::median;

// Streams `bytes` of per-vertex data once on every core: each of `vertices`
// reads its share of one array and writes three floats, as a relight must at
// least.
class Stream {
 public:
  Stream(Eigen::Index vertices, double bytes) : vertices_(vertices) {
    const Eigen::Index out_floats = 3 * vertices;
    const Eigen::Index in_floats =
        std::max<Eigen::Index>(vertices, Eigen::Index(bytes / sizeof(float)) - out_floats);
    per_vertex_ = std::max<Eigen::Index>(1, in_floats / vertices);
    in_.assign(static_cast<std::size_t>(per_vertex_ * vertices), 1.f);
    out_.resize(static_cast<std::size_t>(out_floats));
  }
  void operator()() {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, vertices_, 1024), [&](const auto& range) {
      for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
        float sum = 0;
        for (Eigen::Index j = 0; j < per_vertex_; ++j) sum += in_[p * per_vertex_ + j];
        out_[p] = sum;
        out_[vertices_ + p] = sum;
        out_[2 * vertices_ + p] = sum;
      }
    });
    if (out_[0] < 0) std::puts("");
  }

 private:
  Eigen::Index vertices_, per_vertex_;
  std::vector<float> in_, out_;
};

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
    // Two renderers (two contexts), so that neither re-uploads its scene
    // when the other draws: their frames alternate, and the machine's drift
    // hits both alike.
    auto renderer = registry.create<Renderer>("opengl", gl_params);
    auto plain_renderer = registry.create<Renderer>("opengl", gl_params);
    const Camera camera = scene.make_camera(data.mesh);
    const Relit relit = relighting.relight(data.compressed, light, camera);
    RenderInput prt_input = relighting.input(data.compressed, relit, light, camera);
    RenderInput plain = prt_input;
    plain.exit_values = nullptr;
    plain.albedo = Eigen::Vector3f::Ones();  // vertex_radiance includes the albedo
    plain.vertex_radiance = &relit.vertex_radiance;

    renderer->render(prt_input);  // upload and warm up
    plain_renderer->render(plain);
    std::vector<double> prt_frames, plain_frames, constants;
    for (int f = 0; f < frames; ++f) {
      renderer->render(prt_input);
      prt_frames.push_back(renderer->statistics().at("draw_seconds"));
      constants.push_back(renderer->statistics().at("relight_seconds"));
      plain_renderer->render(plain);
      plain_frames.push_back(plain_renderer->statistics().at("draw_seconds"));
    }
    const double prt_frame = median(prt_frames);
    const double plain_frame = median(plain_frames);
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
    const std::string kind = data.transfer.glossy() ? "glossy" : "diffuse";
    const std::string shape = std::to_string(c.clusters()) + "x" + std::to_string(c.components);
    const double gpu_limit = data.transfer.glossy() ? 4.0 : 1.2;
    std::printf(
        "PERF|OpenGL frame, %s %s (llvmpipe: CPU)|%.2f ms (%.1f Hz)|plain draw %.2f ms|%.2f|"
        "%.1f|%s\n",
        kind.c_str(), shape.c_str(), 1e3 * prt_frame, 1 / prt_frame, 1e3 * plain_frame,
        prt_frame / plain_frame, gpu_limit, prt_frame / plain_frame <= gpu_limit ? "PASS" : "FAIL");

    // CPU relighting of every vertex against streaming its per-vertex data
    // once (same sizes, same threads, same run).
    const RelightKernel kernel = relighting.prepare(c);
    const MatrixXfRow* exit_values = data.transfer.glossy() ? &relit.exit_values : nullptr;
    const int cpu_frames = std::max(frames, 200);
    const double bytes = kernel.streamed_bytes(exit_values != nullptr);
    Stream stream(c.vertices(), bytes);
    Eigen::MatrixX3f radiance;  // reused, as a viewer's frame buffer is
    // Alternating, as the GPU frames.
    const auto [relight_s, bound] = bench::alternating_median_seconds(
        cpu_frames,
        [&] {
          kernel.radiance(light, exit_values, radiance);
          if (radiance.rows() == 0) std::puts("");
        },
        [&] { stream(); });
    std::printf("CPU  per-cluster constants, GL path (%lld clusters) %9.3f ms\n",
                static_cast<long long>(c.clusters()), 1e3 * median(constants));
    std::printf("CPU  relight every vertex (constants + sums) %9.3f ms\n", 1e3 * relight_s);
    std::printf("CPU  streaming its %.2f MB of per-vertex data  %9.3f ms\n", bytes / 1e6,
                1e3 * bound);
    std::printf("CPU  relight / streaming ratio %.2f\n", relight_s / bound);
    if (!data.transfer.glossy()) {
      const double ratio = relight_s / bound;
      std::printf("PERF|CPU relight, %s %s RGB|%.3f ms|streaming %.2f MB %.3f ms|%.2f|%.1f|%s\n",
                  kind.c_str(), shape.c_str(), 1e3 * relight_s, bytes / 1e6, 1e3 * bound, ratio,
                  1.3, ratio <= 1.3 ? "PASS" : "FAIL");
      return 0;
    }
    // Glossy (issue 42): while the camera stays, a light change relights
    // the transfer folded toward it (ViewTransfer, t_p . l), against
    // streaming the bytes that frame reads; a camera change folds again.
    std::vector<double> folds;
    for (int f = 0; f < 5; ++f) {
      Stopwatch clock;
      const ViewTransfer folded(c, relit.exit_values);
      folds.push_back(clock.seconds());
    }
    const ViewTransfer view(c, relit.exit_values);
    const double view_bytes = view.streamed_bytes();
    Stream view_stream(c.vertices(), view_bytes);
    const auto [view_s, view_bound] = bench::alternating_median_seconds(
        cpu_frames,
        [&] {
          view.radiance(light, radiance);
          if (radiance.rows() == 0) std::puts("");
        },
        [&] { view_stream(); });
    const double fold = median(folds);
    std::printf("CPU  light change (t_p . l, camera fixed)   %9.3f ms\n", 1e3 * view_s);
    std::printf("CPU  streaming its %.2f MB of t_p          %9.3f ms\n", view_bytes / 1e6,
                1e3 * view_bound);
    std::printf(
        "CPU  camera change (fold t_p + relight)     %9.3f ms  (%.1fx a constants relight)\n",
        1e3 * (fold + view_s), (fold + view_s) / relight_s);
    const double ratio = view_s / view_bound;
    std::printf(
        "PERF|CPU relight, %s %s RGB, light change|%.3f ms|streaming %.2f MB %.3f ms|%.2f|"
        "%.1f|%s\n",
        kind.c_str(), shape.c_str(), 1e3 * view_s, view_bytes / 1e6, 1e3 * view_bound, ratio, 1.5,
        ratio <= 1.5 ? "PASS" : "FAIL");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_view: %s\n", e.what());
    return 1;
  }
}
