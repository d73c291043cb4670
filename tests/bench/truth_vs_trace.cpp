// The Monte Carlo ground truth's throughput against the best known
// occlusion path, in one run (issue 42: the reference at tracing speed):
//
//   bench_truth [mesh.off] [map.exr] [samples] [repeats]
//     defaults: bunny00.off, courtyard.exr turned 90 degrees, 1024, 3
//
// "ground truth": ground_truth_estimate as `prt render --compare` runs it
// for a reference of `samples` per vertex: four independent batches traced
// together (stratified sphere and map samples, each picked per vertex from
// its batch's pool, combined by MIS; one occlusion ray per sample above a
// vertex's tangent plane; its BVH built inside), rays traced per second;
// "anchor": the shared/anchors settings (raw_embree.hpp) on the bake's 1,024
// directions, rays per second; "its rays alone": the ground truth's own rays
// traced without the sampling and shading around them, the trace's share of
// its time. Limit: seconds per ray of the ground truth <= 1.5x the anchor's.
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

// The ground truth's own rays: each vertex, along the Morton curve, picks a
// candidate per stratum from the run's sample pool (draw_sample_pool) and
// traces those above its tangent plane through the bake's trace_visibility, 16
// vertices a call, as ground_truth_estimate does. Picked before timing.
class GroundTruthRays {
 public:
  GroundTruthRays(const prt::Mesh& mesh, const prt::Environment& environment, int side,
                  const std::vector<std::uint64_t>& seeds)
      : mesh_(mesh), caster_(mesh), order_(prt::morton_order(mesh)) {
    const prt::EnvironmentSampler sampler(environment);
    std::vector<prt::SamplePool> pools;
    for (const std::uint64_t seed : seeds)
      pools.push_back(prt::draw_sample_pool(environment, &sampler, side, seed));
    const std::size_t strata = std::size_t(pools.front().strata);
    strata_ = strata * seeds.size();  // every batch's rays of a vertex in one call
    flat_.reserve(order_.size() * strata_ * 3);
    std::vector<std::size_t> picked(strata);
    for (const std::uint32_t v : order_)
      for (std::size_t b = 0; b < seeds.size(); ++b) {
        pools[b].pick(seeds[b], v, picked.data());
        for (const std::size_t entry : picked) {
          const Eigen::Vector3f& d = pools[b].entries[entry].direction;
          flat_.insert(flat_.end(), {d.x(), d.y(), d.z()});
        }
      }
  }
  // The rays traced.
  std::uint64_t trace() const {
    std::atomic<std::uint64_t> rays{0};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, order_.size(), 64), [&](const auto& range) {
          std::vector<std::uint64_t> bits(prt::VisibilityBits::words_for(strata_));
          std::uint64_t traced = 0;
          for (std::size_t i = range.begin(); i < range.end(); i += 16) {
            const std::size_t count = std::min<std::size_t>(16, range.end() - i);
            bits.resize(count * prt::VisibilityBits::words_for(strata_));
            traced += caster_.trace_visibility(mesh_, &order_[i], count, &flat_[i * strata_ * 3],
                                               strata_, bits.data(), nullptr, 3 * strata_);
          }
          rays += traced;
        });
    return rays;
  }

 private:
  const prt::Mesh& mesh_;
  prt::RayCaster caster_;
  std::vector<std::uint32_t> order_;
  std::size_t strata_ = 0;
  std::vector<float> flat_;  // each vertex's picked directions, xyz, in Morton order
};

}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const std::string root = PRT_SOURCE_DIR;
  const std::string mesh_file = argc > 1 ? argv[1] : root + "/data/meshes/bunny00.off";
  const std::string map_file = argc > 2 ? argv[2] : root + "/data/hdri/courtyard.exr";
  const int samples = argc > 3 ? std::stoi(argv[3]) : 1024;
  const int repeats = argc > 4 ? std::stoi(argv[4]) : 3;
  const double limit = 1.5;

  const Mesh mesh = load_mesh(mesh_file);
  Environment environment = Environment::load(map_file);
  if (environment.width() * environment.height() <= 1) {  // its replica draws map pools
    std::fprintf(stderr, "bench_truth: %s: needs a map of more than one texel\n", map_file.c_str());
    return 2;
  }
  environment.set_rotation(rotation_about_up(90.0));  // as scenes/bunny.toml
  const DirectionSet set = DirectionSet::fibonacci(1024);
  const std::vector<std::uint32_t> order = morton_order(mesh);
  const bench::RawSettings anchor = bench::anchor_settings(set.size());

  // Four batches of samples / 4, each side^2 sphere and side^2 map samples
  // per vertex (rounded to whole strata); those above the tangent plane are
  // traced.
  const std::vector<std::uint64_t> seeds = {11, 12, 13, 14};
  const int per_batch = std::max(1, samples / int(seeds.size()));
  const int side = std::max(1, int(std::lround(std::sqrt(per_batch / 2))));
  // The ground truth's kind of rays alone (the trace share of its time).
  const GroundTruthRays rays(mesh, environment, side, seeds);
  std::uint64_t anchor_rays = 0, estimate_rays = 0, replica_rays = 0;
  const std::vector<double> seconds = bench::alternating_medians(
      repeats, {[&] { anchor_rays = bench::raw_trace(mesh, set, order, anchor).rays; },
                [&] {
                  estimate_rays =
                      ground_truth_estimate(mesh, environment, per_batch, seeds, nullptr).rays;
                },
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
  std::printf("mesh %s: %zu vertices; map %s; %d samples per vertex in %zu batches\n",
              mesh_file.c_str(), mesh.vertex_count(), map_file.c_str(), samples, seeds.size());
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
  std::printf(
      "PERF|ground truth, bunny %d samples in 4 batches|%.2f Mrays/s|anchor %.2f "
      "Mrays/s|%.2f|%.1f|%s\n",
      samples, truth_rate * 1e-6, anchor_rate * 1e-6, ratio, limit,
      ratio <= limit ? "PASS" : "FAIL");
  return ratio <= limit ? 0 : 1;
}
