// The generated room of the probe scenes: thick walls, a ceiling and a window.
#include <algorithm>
#include <cmath>

#include "prt/mesh.hpp"
#include "prt/mesh_compose.hpp"

namespace prt {

namespace {

// A closed box [lo, hi] with outward normals, each face a grid of cells no
// larger than `cell` (each face has its own vertices: sharp edges).
Mesh make_cuboid(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float cell) {
  Mesh m;
  const Eigen::Vector3f centre = (lo + hi) / 2, half = (hi - lo) / 2;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {1.f, -1.f}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      // u x v = n: triangles wind counter-clockwise seen from outside.
      Eigen::Vector3f u = Eigen::Vector3f::Zero(), v = Eigen::Vector3f::Zero();
      u[a] = 1;
      v[b] = sign;
      const int cu = std::max(1, int(std::ceil(2 * half[a] / cell)));
      const int cv = std::max(1, int(std::ceil(2 * half[b] / cell)));
      const auto base = static_cast<std::uint32_t>(m.positions.size());
      for (int i = 0; i <= cu; ++i)
        for (int j = 0; j <= cv; ++j) {
          const float s = 2.f * float(i) / float(cu) - 1, t = 2.f * float(j) / float(cv) - 1;
          Eigen::Vector3f p = centre;
          p[axis] += sign * half[axis];
          p[a] += s * half[a];
          p[b] += t * sign * half[b];
          m.positions.push_back(p);
          m.normals.push_back(n);
        }
      auto at = [&](int i, int j) { return base + std::uint32_t(i * (cv + 1) + j); };
      for (int i = 0; i < cu; ++i)
        for (int j = 0; j < cv; ++j) {
          m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
          m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
  return m;
}

}  // namespace

Mesh make_room(int detail) {
  // A 4 x 2.5 x 4 room (inside) with walls 0.2 thick, a ceiling, and a
  // 2 x 1.2 window in the +z wall, on a ground 8 x 8 wide; units are metres.
  const float cell = 0.8f / float(1 << std::clamp(detail, 0, 6));
  const float t = 0.2f, w = 2, height = 2.5f;
  using V = Eigen::Vector3f;
  Mesh room;
  // The ground: a thin closed slab whose top is y = 0.
  Mesh ground = make_cuboid(V(-4, -0.1f, -4), V(4, 0, 4), std::max(cell, 0.25f));
  append(room, ground);
  const V boxes[][2] = {
      {V(-w - t, 0, -w - t), V(-w, height, w + t)},              // -x wall
      {V(w, 0, -w - t), V(w + t, height, w + t)},                // +x wall
      {V(-w, 0, -w - t), V(w, height, -w)},                      // -z wall
      {V(-w, 0, w), V(-1, height, w + t)},                       // +z wall, left of the window
      {V(1, 0, w), V(w, height, w + t)},                         // right of it
      {V(-1, 0, w), V(1, 0.7f, w + t)},                          // below it
      {V(-1, 1.9f, w), V(1, height, w + t)},                     // above it
      {V(-w - t, height, -w - t), V(w + t, height + t, w + t)},  // ceiling
  };
  for (const auto& box : boxes) append(room, make_cuboid(box[0], box[1], cell));
  return room;
}

}  // namespace prt
