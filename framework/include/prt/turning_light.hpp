// The scene's light turning about the up axis, kept in the light basis: the
// one rule of the viewer, bench and Python for a light under rotation. A basis
// that rotates its coefficients rotates them; a lattice basis rotates its
// samples (Nowrouzezahrai et al., section 5); any other projects the rotated
// map again.
#pragma once
#include <optional>
#include <string>

#include "prt/environment.hpp"
#include "prt/lattice_lighting.hpp"
#include "prt/relighting.hpp"

namespace prt {

class TurningLight {
 public:
  // `environment` at the scene's rotation; `relighting` must outlive this.
  TurningLight(const Relighting& relighting, Environment environment);
  // The light vector (N_i x 3) turned `degrees` about the up axis from the
  // scene's rotation; environment() is then turned alike (a background).
  Eigen::MatrixX3d at(double degrees);
  const Environment& environment() const { return environment_; }
  // How the basis receives the turn, for logs and panels.
  std::string rule() const;

 private:
  const Relighting& relighting_;
  Environment environment_;
  Eigen::Matrix3d scene_rotation_;
  Eigen::MatrixX3d base_;  // at the scene's rotation
  std::optional<LatticeRotation> lattice_;
};

}  // namespace prt
