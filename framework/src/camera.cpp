#include "prt/camera.hpp"

#include <cmath>

#include "prt/mesh.hpp"

namespace prt {

Camera Camera::framing(const Mesh& mesh, int width, int height, float fov_degrees) {
  Camera c;
  c.width = width, c.height = height, c.fov_degrees = fov_degrees;
  const Eigen::Vector3f lo = mesh.bounds_min(), hi = mesh.bounds_max();
  c.target = 0.5f * (lo + hi);
  const float radius = 0.5f * (hi - lo).norm();
  const float half_fov = 0.5f * fov_degrees * float(M_PI) / 180.f;
  const float distance = radius / std::sin(half_fov) * 1.05f;
  c.position = c.target + Eigen::Vector3f(0, 0.15f, 1).normalized() * distance;
  return c;
}

}  // namespace prt
