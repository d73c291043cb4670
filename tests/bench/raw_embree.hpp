// The best raw Embree path we found for the bake's rays, written directly
// against Embree (independent of the project's RayCaster), so that the bake
// is compared with what the library can do on the same rays.
//
// Settings (docs/performance.md justifies each): one BVH of the mesh built
// with `quality`, the robust flag as asked; per task a block of vertices in
// Morton order; for each vertex only the directions above its tangent plane;
// rays streamed through rtcOccluded1M with the incoherent flag in chunks of
// `chunk`; nothing kept but the count of escaping rays.
#pragma once
#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"

namespace prt::bench {

struct RawSettings {
  bool robust = true;
  RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;
  unsigned chunk = 1024;
  std::size_t block = 64;   // vertices per task
  bool ftz = false;         // flush denormals to zero on every tracing thread
  bool per_vertex = false;  // one rtcOccluded1M call per vertex instead of full chunks
};

struct RawResult {
  std::uint64_t rays = 0, escaped = 0;
};

// The anchor's settings (../shared/anchors/README.md), the fastest path
// measured on these machines, for `directions` per vertex.
inline RawSettings anchor_settings(Eigen::Index directions, bool robust = false) {
  RawSettings settings;
  settings.robust = robust;
  settings.quality = RTC_BUILD_QUALITY_HIGH;
  settings.ftz = true;
  settings.per_vertex = true;
  settings.chunk = static_cast<unsigned>(directions);
  return settings;
}

// One BVH of the mesh's triangles.
inline RTCScene build_scene(RTCDevice device, const Mesh& mesh, bool robust,
                            RTCBuildQuality quality) {
  RTCScene scene = rtcNewScene(device);
  if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, quality);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry, quality);
  auto* positions = static_cast<float*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                              3 * sizeof(float), mesh.positions.size()));
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    for (int c = 0; c < 3; ++c) positions[3 * v + c] = mesh.positions[v][c];
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) indices[3 * t + c] = mesh.triangles[t][c];
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  return scene;
}

inline RawResult raw_trace(const Mesh& mesh, const DirectionSet& set,
                           const std::vector<std::uint32_t>& order, const RawSettings& settings) {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = build_scene(device, mesh, settings.robust, settings.quality);

  std::vector<float> directions(3 * set.size());
  for (Eigen::Index k = 0; k < set.size(); ++k)
    for (int c = 0; c < 3; ++c) directions[3 * k + c] = float(set.directions(k, c));
  const float offset = std::max(1e-6f, 1e-4f * (mesh.bounds_max() - mesh.bounds_min()).norm());
  std::atomic<std::uint64_t> rays{0}, escaped{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), settings.block),
                    [&](const auto& range) {
                      if (settings.ftz) {
                        _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
                        _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
                      }
                      std::vector<RTCRay> stream(std::max<std::size_t>(settings.chunk, set.size()));
                      RTCIntersectContext context;
                      rtcInitIntersectContext(&context);
                      context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
                      std::uint64_t cast = 0, out = 0;
                      unsigned filled = 0;
                      auto flush = [&] {
                        rtcOccluded1M(scene, &context, stream.data(), filled, sizeof(RTCRay));
                        for (unsigned i = 0; i < filled; ++i) out += stream[i].tfar >= 0.f;
                        cast += filled;
                        filled = 0;
                      };
                      for (std::size_t i = range.begin(); i < range.end(); ++i) {
                        const Eigen::Vector3f n = mesh.normals[order[i]];
                        const Eigen::Vector3f o = mesh.positions[order[i]] + offset * n;
                        for (Eigen::Index k = 0; k < set.size(); ++k) {
                          const float* d = &directions[3 * k];
                          if (n.x() * d[0] + n.y() * d[1] + n.z() * d[2] <= 0.f) continue;
                          RTCRay& r = stream[filled];
                          r.org_x = o.x(), r.org_y = o.y(), r.org_z = o.z();
                          r.dir_x = d[0], r.dir_y = d[1], r.dir_z = d[2];
                          r.tnear = 0.f, r.tfar = INFINITY, r.time = 0.f;
                          r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
                          if (++filled == settings.chunk) flush();
                        }
                        if (settings.per_vertex && filled) flush();
                      }
                      if (filled) flush();
                      rays += cast;
                      escaped += out;
                    });
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return {rays, escaped};
}

}  // namespace prt::bench
