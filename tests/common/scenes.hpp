// Small generated scenes shared by the unit tests and the conformance kit.
#pragma once
#include <Eigen/Core>
#include <algorithm>

#include "prt/mesh.hpp"
#include "prt/transport.hpp"

namespace prt::test {

// A unit icosphere over a plane: convex on top, self-shadowing below, so
// visibility varies from vertex to vertex.
inline Mesh sphere_over_plane(int sphere_detail = 2, int plane_cells = 6, float plane_size = 5.f,
                              float plane_height = -1.1f) {
  Mesh scene = make_sphere(sphere_detail);
  const Mesh plane = make_plane(plane_cells, plane_size);
  const auto base = static_cast<std::uint32_t>(scene.positions.size());
  for (std::size_t v = 0; v < plane.vertex_count(); ++v) {
    scene.positions.push_back(plane.positions[v] + Eigen::Vector3f(0, plane_height, 0));
    scene.normals.push_back(plane.normals[v]);
  }
  for (auto t : plane.triangles) scene.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return scene;
}

// Traces and keeps only the visibility bits (no projection).
inline TransportResult trace_visibility_only(const Mesh& mesh, const DirectionSet& set) {
  TransportOptions options;
  options.keep_visibility = true;
  return diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), options, nullptr);
}

// The bits of vertices [first, last) of `all` (a rank's shard of them).
inline VisibilityBits shard_bits(const VisibilityBits& all, std::size_t first, std::size_t last) {
  VisibilityBits part(last - first, all.directions());
  const std::size_t words = VisibilityBits::words_for(all.directions());
  for (std::size_t v = first; v < last; ++v)
    std::copy_n(all.words(v), words, part.words(v - first));
  return part;
}

}  // namespace prt::test
