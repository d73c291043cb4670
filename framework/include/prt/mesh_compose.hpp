// Scenes of several meshes: a mesh placed by the scene, and meshes joined
// into one (one ray-tracing structure, one set of vertices).
#pragma once
#include <Eigen/Core>

#include "prt/mesh.hpp"

namespace prt {

// A copy of `mesh` scaled uniformly so that the longest side of its bounding
// box is `size`, and moved so that the bottom centre of its bounds (least y,
// centre in x and z) is at `base`: a mesh stood on a floor at a point.
Mesh placed(const Mesh& mesh, const Eigen::Vector3f& base, float size);

// Appends `part`'s vertices and triangles to `into`.
void append(Mesh& into, const Mesh& part);

}  // namespace prt
