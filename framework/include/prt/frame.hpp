// Local frames of the vertices: where glossy transfer and exit radiance live.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "prt/mesh.hpp"

namespace prt {

// Orthonormal frame per vertex: rows tangent, bitangent, normal, so that
// frame * world = local. The tangent is world +y projected onto the tangent
// plane (+x near the poles), which fixes the axis of anisotropic BRDFs.
using Frame = Eigen::Matrix3d;
// The frame of one normal (any length), by the rule above.
Frame tangent_frame(const Eigen::Vector3d& normal);
std::vector<Frame> tangent_frames(const Mesh& mesh);

// Clamps a local direction to the upper hemisphere and normalises it: exit
// bases are defined there only.
Eigen::Vector3d upper_hemisphere(Eigen::Vector3d local);

// The view direction at each vertex in its local frame (z clamped to the
// upper hemisphere), for a camera at `eye`: s x 3, one row per vertex.
Eigen::MatrixXd local_view_directions(const Mesh& mesh, const std::vector<Frame>& frames,
                                      const Eigen::Vector3f& eye);

}  // namespace prt
