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
};

}  // namespace prt
