#include "prt/turning_light.hpp"

#include "prt/basis.hpp"

namespace prt {

TurningLight::TurningLight(const Relighting& relighting, Environment environment)
    : relighting_(relighting),
      environment_(std::move(environment)),
      scene_rotation_(environment_.rotation()),
      base_(relighting.light(environment_)),
      lattice_(LatticeRotation::of(relighting.basis(), environment_)) {}

Eigen::MatrixX3d TurningLight::at(double degrees) {
  const Eigen::Matrix3d turn = rotation_about_up(degrees);
  environment_.set_rotation(turn * scene_rotation_);
  const Basis& basis = relighting_.basis();
  if (basis.can_rotate()) return basis.rotation_matrix(turn) * base_;
  if (lattice_) return lattice_->light(environment_.rotation());
  return relighting_.light(environment_);
}

std::string TurningLight::rule() const {
  if (relighting_.basis().can_rotate()) return "rotation of the basis's coefficients";
  if (lattice_)
    return "rotation of the " + std::to_string(lattice_->resolution()) +
           "^2 x 6 lattice samples (Nowrouzezahrai et al. 5)";
  return "re-projection of the rotated map";
}

}  // namespace prt
