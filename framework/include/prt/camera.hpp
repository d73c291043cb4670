// A pinhole camera.
#pragma once
#include <Eigen/Core>

namespace prt {

struct Mesh;

struct Camera {
  Eigen::Vector3f position{0, 0, 3};
  Eigen::Vector3f target{0, 0, 0};
  Eigen::Vector3f up{0, 1, 0};
  float fov_degrees = 40.0f;
  int width = 640, height = 480;

  // Looks at the mesh's bounding box from the +z side, framing it fully.
  static Camera framing(const Mesh& mesh, int width, int height, float fov_degrees = 40.0f);

  // World direction through image point (x, y) in pixels (pixel centres at +0.5).
  Eigen::Vector3f ray(float x, float y) const;
};

// 4x4 view-projection matrix of the camera (OpenGL conventions, near/far
// chosen from the mesh bounds): shared by the software and OpenGL renderers
// so their images line up.
Eigen::Matrix4f view_projection(const Camera& camera, const Mesh& mesh);

}  // namespace prt
