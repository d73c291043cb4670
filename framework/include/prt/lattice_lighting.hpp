// Lighting on a cube-map lattice, for bases that live on one (eigentransport,
// Haar): distant light rotated by rotating the lattice with bilinear
// interpolation of the canonical samples (Nowrouzezahrai et al. §5). Local
// point lights are prt/point_lights.hpp.
#pragma once
#include <Eigen/Core>
#include <optional>

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

// Distant light for a basis that lives on a cube-map lattice and cannot
// rotate its coefficients (eigentransport, Haar): the canonical samples are
// made once, and each rotation resamples them on the lattice and projects
// with the basis's own projection (§5), instead of re-sampling the map.
class LatticeRotation {
 public:
  // Nothing unless the basis's native directions are a cube map and it has
  // no rotation capability.
  static std::optional<LatticeRotation> of(const Basis& basis, const Environment& environment);
  // The light vector (n x 3) of the environment rotated by `rotation`.
  Eigen::MatrixX3d light(const Eigen::Matrix3d& rotation) const;
  int resolution() const { return resolution_; }

 private:
  const Basis* basis_ = nullptr;
  int resolution_ = 0;
  DirectionSet lattice_;
  Eigen::MatrixX3d canonical_;
};

}  // namespace prt
