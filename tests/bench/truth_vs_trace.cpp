// The Monte Carlo ground truth's throughput against the best known
// occlusion path, in one run (issue 42: the reference at tracing speed):
//
//   bench_truth [mesh.off] [map.exr] [samples] [repeats]
//     defaults: bunny00.off, courtyard.exr turned 90 degrees, 256, 3
//
// "ground truth": ground_truth_radiance (stratified cosine and map samples
// combined by MIS, one occlusion ray each), rays per second; "anchor": the
// shared/anchors settings (raw_embree.hpp) on the bake's 1,024 directions,
// rays per second. Limit: seconds per ray of the ground truth <= 1.5x the
// anchor's.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <string>

#include "prt/direction_set.hpp"
#include "prt/environment.hpp"
#include "prt/ground_truth.hpp"
#include "prt/mesh.hpp"
#include "prt/transport.hpp"
#include "raw_embree.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

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

  std::uint64_t anchor_rays = 0;
  const std::vector<double> seconds = bench::alternating_medians(
      repeats, {[&] { anchor_rays = bench::raw_trace(mesh, set, order, anchor).rays; },
                [&] { ground_truth_radiance(mesh, environment, samples, 1, nullptr); }});
  // Every sample is one ray (both strategies; samples rounds to whole strata).
  const int side = std::max(1, int(std::lround(std::sqrt(samples / 2))));
  const double truth_rays = double(mesh.vertex_count()) * 2 * side * side;
  const double anchor_rate = anchor_rays / seconds[0], truth_rate = truth_rays / seconds[1];
  const double ratio = anchor_rate / truth_rate;
  std::printf("mesh %s: %zu vertices; map %s; %d samples per vertex\n", mesh_file.c_str(),
              mesh.vertex_count(), map_file.c_str(), samples);
  std::printf("anchor occlusion : %8.3f s  %6.2f Mrays/s (median of %d)\n", seconds[0],
              anchor_rate * 1e-6, repeats);
  std::printf("ground truth     : %8.3f s  %6.2f Mrays/s\n", seconds[1], truth_rate * 1e-6);
  std::printf("seconds per ray, ground truth / anchor: %.2f (limit %.1f: %s)\n", ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  std::printf("PERF|ground truth, bunny %d samples|%.2f Mrays/s|anchor %.2f Mrays/s|%.2f|%.1f|%s\n",
              samples, truth_rate * 1e-6, anchor_rate * 1e-6, ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  return ratio <= limit ? 0 : 1;
}
