#include "prt/frame.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace prt {

Frame tangent_frame(const Eigen::Vector3d& normal) {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d axis =
      std::abs(n.y()) < 0.999 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d t = (axis - axis.dot(n) * n).normalized();
  Frame frame;
  frame.row(0) = t;
  frame.row(1) = n.cross(t);
  frame.row(2) = n;
  return frame;
}

std::vector<Frame> tangent_frames(const Mesh& mesh) {
  std::vector<Frame> frames(mesh.vertex_count());
  for (std::size_t v = 0; v < frames.size(); ++v)
    frames[v] = tangent_frame(mesh.normals[v].cast<double>());
  return frames;
}

Eigen::Vector3d upper_hemisphere(Eigen::Vector3d local) {
  // Just above the horizon rather than on it: BRDFs vanish at z = 0, and a
  // vertex seen edge-on should keep its grazing radiance.
  local.z() = std::max(local.z(), 1e-3 * local.norm());
  const double norm = local.norm();
  return norm > 1e-12 ? Eigen::Vector3d(local / norm) : Eigen::Vector3d::UnitZ();
}

Eigen::MatrixXd local_view_directions(const Mesh& mesh, const std::vector<Frame>& frames,
                                      const Eigen::Vector3f& eye) {
  Eigen::MatrixXd views(static_cast<Eigen::Index>(mesh.vertex_count()), 3);
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    views.row(Eigen::Index(v)) =
        upper_hemisphere(frames[v] * (eye - mesh.positions[v]).cast<double>()).transpose();
  return views;
}

}  // namespace prt
