// Lighting on a cube-map lattice, for bases that live on one (eigentransport,
// Haar): distant light rotated by rotating the lattice with bilinear
// interpolation of the canonical samples (Nowrouzezahrai et al. §5), and local
// point lights by the nearest lattice direction per vertex (§4.2.1).
#pragma once
#include <Eigen/Core>

#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

// The environment averaged over each texel of a 6 x R x R cube map (s x 3):
// the canonical samples, computed once. The environment's own rotation is
// ignored (it is what rotate_lattice_lighting applies).
Eigen::MatrixX3d lattice_lighting(const Environment& environment, int resolution);

// Samples of the rotated light L(R^T w) at every lattice direction, by
// bilinear interpolation of the canonical samples within a face (clamped at
// face edges).
Eigen::MatrixX3d rotate_lattice_lighting(const Eigen::MatrixX3d& samples, int resolution,
                                         const Eigen::Matrix3d& rotation);

// Exit radiance (v x 3, albedo 1) from a point light at `position` of
// `intensity` (no falloff, as the paper): each vertex looks up the lattice
// direction nearest to the light, so its light vector is intensity x the basis
// functions there: e_p = t_p . (I b(w_k(p))).
Eigen::MatrixX3f point_light_radiance(const Mesh& mesh, const CompressedTransfer& transfer,
                                      const Basis& basis, int resolution,
                                      const Eigen::Vector3d& position,
                                      const Eigen::Vector3f& intensity);

}  // namespace prt
