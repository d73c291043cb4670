// Bake throughput against the best known raw Embree path on the same rays,
// in one run.
//
//   bench_bake [mesh.off] [rays] [order] [repeats]
//
// Three paths trace exactly the rays the bake casts (directions above each
// vertex's tangent plane, vertices in Morton order), alternating:
// - "anchor": the settings of the peer benchmark in ../shared/anchors/, the
//   fastest path measured on these machines (one rtcOccluded1M call per
//   vertex, incoherent flag, FTZ/DAZ on every thread, a high-quality BVH, no
//   robust flag), reproduced in raw_embree.hpp;
// - "anchor + robust": the same with RTC_SCENE_FLAG_ROBUST, the watertight
//   intersector the bake keeps (docs/performance.md, "Tracing");
// - "bake": the full transfer stage (BVH, rays, visibility bits, SH
//   projection of the visible rays).
// The raw paths count rays and build their BVH inside the timing, as the
// bake does. Limit (issue 42): bake / (anchor + robust) <= 1.1; the robust
// flag's cost, anchor + robust / anchor, is printed beside it.
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
  const bench::RawSettings anchor = bench::anchor_settings(set.size());
  const bench::RawSettings anchor_robust = bench::anchor_settings(set.size(), true);
  const Eigen::MatrixXd projection = set.weights.asDiagonal() * sh::evaluate(order, set.directions);

  std::uint64_t rays_anchor = 0, rays_robust = 0, rays_bake = 0;
  const std::vector<double> seconds = bench::alternating_medians(
      repeats,
      {[&] { rays_anchor = bench::raw_trace(mesh, set, order_of_vertices, anchor).rays; },
       [&] { rays_robust = bench::raw_trace(mesh, set, order_of_vertices, anchor_robust).rays; },
       [&] {
         rays_bake = diffuse_transfer(mesh, set, projection, {true, false}, nullptr).rays_cast;
       }});
  const double anchor_s = seconds[0], robust_s = seconds[1], bake_s = seconds[2];
  const double ratio = bake_s / robust_s;
  const bool same_rays = rays_anchor == rays_bake && rays_robust == rays_bake;
  std::printf("rays per run: anchor %llu, anchor + robust %llu, bake %llu%s\n",
              (unsigned long long)rays_anchor, (unsigned long long)rays_robust,
              (unsigned long long)rays_bake, same_rays ? " (same rays)" : " (MISMATCH)");
  auto line = [&](const char* name, double s, std::uint64_t n) {
    std::printf("%-22s: %8.3f s  %6.2f Mrays/s (median of %d)\n", name, s, n / s * 1e-6, repeats);
  };
  line("anchor (no robust)", anchor_s, rays_anchor);
  line("anchor + robust", robust_s, rays_robust);
  line("bake (trace+SH)", bake_s, rays_bake);
  std::printf("robust flag's cost    : %8.3f x the anchor\n", robust_s / anchor_s);
  std::printf("bake / anchor         : %8.3f (without the robust flag)\n", bake_s / anchor_s);
  std::printf("bake / anchor+robust  : %8.3f  (limit %.2f: %s)\n", ratio, limit,
              ratio <= limit ? "PASS" : "FAIL");
  std::printf("PERF|bake, bunny %d rays order %d|%.3f s|anchor+robust %.3f s|%.3f|%.2f|%s\n", rays,
              order, bake_s, robust_s, ratio, limit, ratio <= limit && same_rays ? "PASS" : "FAIL");
  std::printf("PERF|anchor (shared/anchors settings), %d rays|%.3f s|robust flag %.3f s|%.3f|-|-\n",
              rays, anchor_s, robust_s, robust_s / anchor_s);
  return ratio <= limit && same_rays ? 0 : 1;
}
