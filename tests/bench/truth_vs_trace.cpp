// The Monte Carlo ground truth's throughput against the best known
// occlusion path, in one run (issue 42: the reference at tracing speed):
//
//   bench_truth [mesh.off] [map.exr] [samples] [repeats]
//     defaults: bunny00.off, courtyard.exr turned 90 degrees, 256, 3
//
// "ground truth": ground_truth_estimate (stratified sphere and map samples
// shared by blocks of nearby vertices, combined by MIS, one occlusion ray per
// sample above a vertex's tangent plane), rays traced per second; "anchor": the
// shared/anchors settings (raw_embree.hpp) on the bake's 1,024 directions,
// rays per second; "its rays alone": the ground truth's own rays traced
// without the sampling and shading around them, the trace's share of its
// time. Limit: seconds per ray
// of the ground truth <= 1.5x the anchor's.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <atomic>
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

// The ground truth's own rays: each block of kSharedBlock vertices along the
// Morton curve shares one sample set (draw_shared_samples), and each vertex
// traces the set's directions above its tangent plane through the bake's
// trace_visibility, as ground_truth_estimate does. Drawn before timing.
class GroundTruthRays {
 public:
  GroundTruthRays(const prt::Mesh& mesh, const prt::Environment& environment, int side)
      : mesh_(mesh), caster_(mesh), order_(prt::morton_order(mesh)) {
    const prt::EnvironmentSampler sampler(environment);
    for (std::size_t b = 0; b * prt::kSharedBlock < mesh.vertex_count(); ++b) {
      const prt::SharedSamples shared = prt::draw_shared_samples(environment, &sampler, side, 1, b);
      std::vector<float> flat;
      for (const Eigen::Vector3f& d : shared.directions)
        flat.insert(flat.end(), {d.x(), d.y(), d.z()});
      sets_.push_back(std::move(flat));
    }
  }
  // The rays traced.
  std::uint64_t trace() const {
    std::atomic<std::uint64_t> rays{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sets_.size(), 1), [&](const auto& range) {
      std::vector<std::uint64_t> bits;
      for (std::size_t b = range.begin(); b < range.end(); ++b) {
        const std::size_t first = b * prt::kSharedBlock, s = sets_[b].size() / 3;
        const std::size_t count = std::min(mesh_.vertex_count() - first, prt::kSharedBlock);
        bits.resize(count * prt::VisibilityBits::words_for(s));
        rays += caster_.trace_visibility(mesh_, order_.data() + first, count, sets_[b].data(), s,
                                         bits.data());
      }
    });
    return rays;
  }

 private:
  const prt::Mesh& mesh_;
  prt::RayCaster caster_;
  std::vector<std::uint32_t> order_;
  std::vector<std::vector<float>> sets_;  // each block's directions, xyz
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

  // Per vertex side^2 sphere and side^2 map samples (samples rounds to whole
  // strata); those above the tangent plane are traced.
  const int side = std::max(1, int(std::lround(std::sqrt(samples / 2))));
  // The ground truth's kind of rays alone (the trace share of its time).
  const GroundTruthRays rays(mesh, environment, side);
  std::uint64_t anchor_rays = 0, estimate_rays = 0, replica_rays = 0;
  const std::vector<double> seconds = bench::alternating_medians(
      repeats,
      {[&] { anchor_rays = bench::raw_trace(mesh, set, order, anchor).rays; },
       [&] { estimate_rays = ground_truth_estimate(mesh, environment, samples, 1, nullptr).rays; },
       [&] { replica_rays = rays.trace(); }});
  if (estimate_rays != replica_rays) {
    std::fprintf(stderr, "bench_truth: the ground truth traced %llu rays, its replica %llu\n",
                 static_cast<unsigned long long>(estimate_rays),
                 static_cast<unsigned long long>(replica_rays));
    return 2;
  }
  const double truth_rays = double(estimate_rays);
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
