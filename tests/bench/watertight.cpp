// What Embree's robust flag (RTC_SCENE_FLAG_ROBUST) buys, per mesh:
//
//   bench_watertight [rays] [mesh.off ...]   # defaults: 1024, six CGAL meshes
//
// - bake rays: the bake's own visibility rays (directions above each
//   vertex's tangent plane) traced with and without the flag; the rays whose
//   answer differs;
// - edge rays: one ray per interior edge, aimed from outside the surface
//   along the mean normal of its two triangles exactly at the edge's
//   midpoint. On a closed, consistently oriented mesh it must hit one of the
//   two triangles within its distance; a miss slipped between them (a leak).
// The cost of the flag is bench_bake's "robust flag's cost" row.
#include <embree3/rtcore.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "raw_embree.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {

using namespace prt;

class Tracer {
 public:
  Tracer(const Mesh& mesh, bool robust)
      : device_(rtcNewDevice(nullptr)),
        scene_(bench::build_scene(device_, mesh, robust, RTC_BUILD_QUALITY_MEDIUM)) {}
  ~Tracer() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  Tracer(const Tracer&) = delete;
  Tracer& operator=(const Tracer&) = delete;

  // Distance to the first hit, or infinity.
  float first_hit(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction) const {
    RTCRayHit rh{};
    rh.ray.org_x = origin.x(), rh.ray.org_y = origin.y(), rh.ray.org_z = origin.z();
    rh.ray.dir_x = direction.x(), rh.ray.dir_y = direction.y(), rh.ray.dir_z = direction.z();
    rh.ray.tfar = INFINITY, rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene_, &context, &rh);
    return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
  }

 private:
  RTCDevice device_;
  RTCScene scene_;
};

Eigen::Vector3f face_normal(const Mesh& mesh, std::size_t t) {
  const auto& tri = mesh.triangles[t];
  return (mesh.positions[tri[1]] - mesh.positions[tri[0]])
      .cross(mesh.positions[tri[2]] - mesh.positions[tri[0]])
      .normalized();
}

struct Counts {
  std::size_t bake_rays = 0, bake_differ = 0, edges = 0, leaks_plain = 0, leaks_robust = 0;
};

Counts measure(const Mesh& mesh, const DirectionSet& set) {
  const Tracer plain(mesh, false), robust(mesh, true);
  Counts counts;
  const float offset = std::max(1e-6f, 1e-4f * (mesh.bounds_max() - mesh.bounds_min()).norm());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3f n = mesh.normals[v], o = mesh.positions[v] + offset * n;
    for (Eigen::Index k = 0; k < set.size(); ++k) {
      const Eigen::Vector3f d = set.directions.row(k).cast<float>();
      if (n.dot(d) <= 0.f) continue;
      ++counts.bake_rays;
      counts.bake_differ += std::isinf(plain.first_hit(o, d)) != std::isinf(robust.first_hit(o, d));
    }
  }
  std::map<std::pair<unsigned, unsigned>, std::vector<std::size_t>> faces_of_edge;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      unsigned a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
      faces_of_edge[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  const float distance = 1e-2f * (mesh.bounds_max() - mesh.bounds_min()).norm();
  for (const auto& [edge, faces] : faces_of_edge) {
    if (faces.size() != 2) continue;
    const Eigen::Vector3f n = face_normal(mesh, faces[0]) + face_normal(mesh, faces[1]);
    if (n.norm() < 0.5f) continue;  // a fold: no outside direction through the edge
    const Eigen::Vector3f mid = 0.5f * (mesh.positions[edge.first] + mesh.positions[edge.second]);
    const Eigen::Vector3f d = -n.normalized(), o = mid - distance * d;
    ++counts.edges;
    // Something nearer than the edge (another part of the mesh) also hides it.
    counts.leaks_plain += plain.first_hit(o, d) > 1.001f * distance;
    counts.leaks_robust += robust.first_hit(o, d) > 1.001f * distance;
  }
  return counts;
}

}  // namespace

int main(int argc, char** argv) {
  const int rays = argc > 1 ? std::stoi(argv[1]) : 1024;
  std::vector<std::string> meshes;
  for (int i = 2; i < argc; ++i) meshes.emplace_back(argv[i]);
  if (meshes.empty())
    for (const char* name : {"bunny00.off", "armadillo.off", "ChineseDragon-10kv.off",
                             "elephant.off", "fandisk.off", "knot1.off"})
      meshes.push_back(std::string(PRT_SOURCE_DIR) + "/data/meshes/" + name);
  const DirectionSet set = DirectionSet::fibonacci(rays);
  std::printf("%-24s %12s %14s %8s %12s %12s\n", "mesh", "bake rays", "differ", "edges",
              "leaks plain", "leaks robust");
  for (const auto& file : meshes) {
    const Mesh mesh = load_mesh(file);
    const Counts c = measure(mesh, set);
    const std::string name = file.substr(file.find_last_of('/') + 1);
    std::printf("%-24s %12zu %14zu %8zu %12zu %12zu\n", name.c_str(), c.bake_rays, c.bake_differ,
                c.edges, c.leaks_plain, c.leaks_robust);
    std::fflush(stdout);
  }
}
