// The Monte Carlo ground truth's throughput against the best known
// occlusion path, in one run (issue 42: the reference at tracing speed):
//
//   bench_truth [mesh.off] [map.exr] [samples] [repeats]
//     defaults: bunny00.off, courtyard.exr turned 90 degrees, 256, 3
//
// "ground truth": ground_truth_radiance (stratified cosine and map samples
// combined by MIS, one occlusion ray each), rays per second; "anchor": the
// shared/anchors settings (raw_embree.hpp) on the bake's 1,024 directions,
// rays per second; "its rays alone": the ground truth's own kind of rays
// (random per vertex, 2 x side^2 a call) traced without the sampling and
// shading around them, the trace's share of its time. Limit: seconds per ray
// of the ground truth <= 1.5x the anchor's.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/environment.hpp"
#include "prt/environment_sampler.hpp"
#include "prt/ground_truth.hpp"
#include "prt/mesh.hpp"
#include "prt/transport.hpp"
#include "raw_embree.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {

// Rays of the ground truth's two strategies, stratified and jittered as it
// draws them, stored per vertex, and traced as it traces them (one
// occluded() call per vertex, vertices in parallel blocks of 16).
class GroundTruthRays {
 public:
  GroundTruthRays(const prt::Mesh& mesh, const prt::Environment& environment, int per_vertex,
                  int cosine)
      : caster_(mesh), per_vertex_(per_vertex), vertices_(mesh.vertex_count()) {
    const prt::EnvironmentSampler sampler(environment);
    const int side = int(std::lround(std::sqrt(cosine)));
    origins_.resize(vertices_ * per_vertex * 3);
    directions_.resize(origins_.size());
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> jitter(0.0, 1.0);
    for (std::size_t v = 0; v < vertices_; ++v) {
      const prt::CosineHemisphere hemisphere(mesh.normals[v].cast<double>());
      const Eigen::Vector3f o = mesh.positions[v] + caster_.offset() * mesh.normals[v];
      for (int k = 0; k < per_vertex; ++k) {
        const int stratum = k % cosine;
        const double u1 = (stratum / side + jitter(rng)) / side;
        const double u2 = (stratum % side + jitter(rng)) / side;
        const Eigen::Vector3d d =
            k < cosine ? hemisphere.sample(u1, u2) : sampler.draw(u1, u2).direction;
        for (int c = 0; c < 3; ++c) {
          origins_[(v * per_vertex + k) * 3 + c] = o[c];
          directions_[(v * per_vertex + k) * 3 + c] = float(d[c]);
        }
      }
    }
  }
  void trace() const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices_, 16), [&](const auto& range) {
      std::vector<std::uint8_t> escaped(static_cast<std::size_t>(per_vertex_), 0);
      for (std::size_t v = range.begin(); v < range.end(); ++v) {
        const std::size_t at = v * per_vertex_ * 3;
        caster_.occluded(&origins_[at], &directions_[at], std::size_t(per_vertex_), escaped.data());
      }
    });
  }

 private:
  prt::RayCaster caster_;
  int per_vertex_;
  std::size_t vertices_;
  std::vector<float> origins_, directions_;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const std::string root = PRT_SOURCE_DIR;
  const std::string mesh_file = argc > 1 ? argv[1] : root + "/data/meshes/bunny00.off";
  const std::string map_file = argc > 2 ? argv[2] : root + "/data/hdri/courtyard.exr";
  const int samples = argc > 3 ? std::stoi(argv[3]) : 256;
  const int repeats = argc > 4 ? std::stoi(argv[4]) : 3;
  const double limit = 1.5;

  const Mesh mesh = load_mesh(mesh_file);
  Environment environment = Environment::load(map_file);
  environment.set_rotation(rotation_about_up(90.0));  // as scenes/bunny.toml
  const DirectionSet set = DirectionSet::fibonacci(1024);
  const std::vector<std::uint32_t> order = morton_order(mesh);
  const bench::RawSettings anchor = bench::anchor_settings(set.size());

  // Every sample is one ray (both strategies; samples rounds to whole strata).
  const int side = std::max(1, int(std::lround(std::sqrt(samples / 2))));
  const double truth_rays = double(mesh.vertex_count()) * 2 * side * side;
  // The ground truth's kind of rays alone (the trace share of its time):
  // per vertex side^2 cosine and side^2 map samples, drawn before timing.
  const GroundTruthRays rays(mesh, environment, 2 * side * side, side * side);
  std::uint64_t anchor_rays = 0;
  const std::vector<double> seconds = bench::alternating_medians(
      repeats, {[&] { anchor_rays = bench::raw_trace(mesh, set, order, anchor).rays; },
                [&] { ground_truth_radiance(mesh, environment, samples, 1, nullptr); },
                [&] { rays.trace(); }});
  const double anchor_rate = anchor_rays / seconds[0], truth_rate = truth_rays / seconds[1];
  const double ratio = anchor_rate / truth_rate;
  std::printf("mesh %s: %zu vertices; map %s; %d samples per vertex\n", mesh_file.c_str(),
              mesh.vertex_count(), map_file.c_str(), samples);
  std::printf("anchor occlusion : %8.3f s  %6.2f Mrays/s (median of %d)\n", seconds[0],
              anchor_rate * 1e-6, repeats);
  std::printf("ground truth     : %8.3f s  %6.2f Mrays/s\n", seconds[1], truth_rate * 1e-6);
  std::printf(
      "its rays alone   : %8.3f s  %6.2f Mrays/s (%.0f%% of the ground truth's time; "
      "%.2fx the anchor's seconds per ray)\n",
      seconds[2], truth_rays / seconds[2] * 1e-6, 100 * seconds[2] / seconds[1],
      anchor_rate / (truth_rays / seconds[2]));
  std::printf("seconds per ray, ground truth / anchor: %.2f (limit %.1f: %s)\n", ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  std::printf("PERF|ground truth, bunny %d samples|%.2f Mrays/s|anchor %.2f Mrays/s|%.2f|%.1f|%s\n",
              samples, truth_rate * 1e-6, anchor_rate * 1e-6, ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  return ratio <= limit ? 0 : 1;
}
