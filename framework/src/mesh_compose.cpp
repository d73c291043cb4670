#include "prt/mesh_compose.hpp"

#include "prt/error.hpp"

namespace prt {

Mesh placed(const Mesh& mesh, const Eigen::Vector3f& base, float size) {
  const Eigen::Vector3f lo = mesh.bounds_min(), hi = mesh.bounds_max();
  const float longest = (hi - lo).maxCoeff();
  if (!(longest > 0) || !std::isfinite(longest))
    throw Error("a mesh to place has no extent (all its vertices coincide)");
  const float scale = size / longest;
  const Eigen::Vector3f bottom((lo.x() + hi.x()) / 2, lo.y(), (lo.z() + hi.z()) / 2);
  Mesh out = mesh;
  for (Eigen::Vector3f& p : out.positions) p = base + scale * (p - bottom);
  return out;  // a uniform scale keeps the unit normals
}

void append(Mesh& into, const Mesh& part) {
  const auto offset = static_cast<std::uint32_t>(into.positions.size());
  into.positions.insert(into.positions.end(), part.positions.begin(), part.positions.end());
  into.normals.insert(into.normals.end(), part.normals.begin(), part.normals.end());
  for (auto triangle : part.triangles) {
    for (auto& index : triangle) index += offset;
    into.triangles.push_back(triangle);
  }
  into.skipped_degenerate_faces += part.skipped_degenerate_faces;
}

}  // namespace prt
