#include "prt/camera.hpp"

#include <Eigen/Geometry>
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

Eigen::Matrix4f view_projection(const Camera& camera, const Mesh& mesh) {
  const Eigen::Vector3f f = (camera.target - camera.position).normalized();
  const Eigen::Vector3f s = f.cross(camera.up).normalized();
  const Eigen::Vector3f u = s.cross(f);
  Eigen::Matrix4f view = Eigen::Matrix4f::Identity();
  view.block<1, 3>(0, 0) = s.transpose();
  view.block<1, 3>(1, 0) = u.transpose();
  view.block<1, 3>(2, 0) = -f.transpose();
  view(0, 3) = -s.dot(camera.position);
  view(1, 3) = -u.dot(camera.position);
  view(2, 3) = f.dot(camera.position);
  // Near and far planes enclose the mesh's bounding sphere.
  const Eigen::Vector3f centre = 0.5f * (mesh.bounds_min() + mesh.bounds_max());
  const float radius = 0.5f * (mesh.bounds_max() - mesh.bounds_min()).norm();
  const float distance = (centre - camera.position).dot(f);
  const float far_plane = std::max(distance + 1.5f * radius, 1e-3f);
  const float near_plane = std::max(distance - 1.5f * radius, far_plane * 1e-4f);
  const float aspect = float(camera.width) / float(camera.height);
  const float t = 1.0f / std::tan(0.5f * camera.fov_degrees * float(M_PI) / 180.f);
  Eigen::Matrix4f projection = Eigen::Matrix4f::Zero();
  projection(0, 0) = t / aspect;
  projection(1, 1) = t;
  projection(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane);
  projection(2, 3) = -2.f * far_plane * near_plane / (far_plane - near_plane);
  projection(3, 2) = -1.f;
  return projection * view;
}

Eigen::Vector3f Camera::ray(float x, float y) const {
  const Eigen::Vector3f f = (target - position).normalized();
  const Eigen::Vector3f s = f.cross(up).normalized();
  const Eigen::Vector3f u = s.cross(f);
  const float t = std::tan(0.5f * fov_degrees * float(M_PI) / 180.f);
  const float aspect = float(width) / float(height);
  const float sx = (2.f * x / width - 1.f) * t * aspect;
  const float sy = (1.f - 2.f * y / height) * t;
  return (f + sx * s + sy * u).normalized();
}

}  // namespace prt
