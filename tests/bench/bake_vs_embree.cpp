// Bake throughput against raw Embree on the same rays, in one run.
//
//   bench_bake [mesh.off] [rays] [order] [repeats]
//
// "raw" is the best raw Embree path we found (raw_embree.hpp, written
// directly against Embree): it builds the BVH and traces exactly the rays the
// bake casts (directions above each vertex's tangent plane, Morton order,
// rtcOccluded1M streams, incoherent) and keeps only a count. "bake" is the
// full transfer stage (BVH, rays, visibility bits, SH projection of the
// visible rays).
// Limit (issue 12): bake / raw <= 1.1 in the same run.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/progress.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"
#include "raw_embree.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

int main(int argc, char** argv) {
  using namespace prt;
  const std::string mesh_file =
      argc > 1 ? argv[1] : std::string(PRT_SOURCE_DIR) + "/data/meshes/bunny00.off";
  const int rays = argc > 2 ? std::stoi(argv[2]) : 1024;
  const int order = argc > 3 ? std::stoi(argv[3]) : 10;
  const int repeats = argc > 4 ? std::stoi(argv[4]) : 3;
  const double limit = 1.1;

  const Mesh mesh = load_mesh(mesh_file);
  const DirectionSet set = DirectionSet::fibonacci(rays);
  std::printf("mesh %s: %zu vertices; %d directions; SH order %d (%d coefficients)\n",
              mesh_file.c_str(), mesh.vertex_count(), rays, order, order * order);

  const std::vector<std::uint32_t> order_of_vertices = morton_order(mesh);
  std::uint64_t rays_raw = 0, rays_bake = 0;
  const auto [raw_s, bake_s] = bench::alternating_median_seconds(
      repeats,
      [&] { rays_raw = bench::raw_trace(mesh, set, order_of_vertices, bench::RawSettings{}).rays; },
      [&] {
        const Eigen::MatrixXd projection =
            set.weights.asDiagonal() * sh::evaluate(order, set.directions);
        rays_bake = diffuse_transfer(mesh, set, projection, {true, false}, nullptr).rays_cast;
      });
  const double ratio = bake_s / raw_s;
  std::printf("rays per run: raw %llu, bake %llu%s\n", (unsigned long long)rays_raw,
              (unsigned long long)rays_bake,
              rays_raw == rays_bake ? " (same rays)" : " (MISMATCH)");
  std::printf("raw Embree trace : %8.3f s  %6.2f Mrays/s (median of %d)\n", raw_s,
              rays_raw / raw_s * 1e-6, repeats);
  std::printf("bake (trace+SH)  : %8.3f s  %6.2f Mrays/s\n", bake_s, rays_bake / bake_s * 1e-6);
  std::printf("ratio bake/raw   : %8.3f  (limit %.2f: %s)\n", ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  std::printf("PERF|bake, bunny %d rays order %d|%.3f s|raw Embree %.3f s|%.3f|%.2f|%s\n", rays,
              order, bake_s, raw_s, ratio, limit,
              ratio <= limit && rays_raw == rays_bake ? "PASS" : "FAIL");
  return ratio <= limit && rays_raw == rays_bake ? 0 : 1;
}
