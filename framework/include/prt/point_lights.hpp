// Local point lights (Nowrouzezahrai et al. §4.2.1, Fig. 7). As in the
// paper, a light has no distance falloff: seen from a vertex it is a cap of
// solid angle Omega (a single direction when its radius is 0) sending
// radiance I / Omega, so a fully lit vertex facing it exits I cos / pi
// (albedo 1) at any distance. Its light vector differs per vertex:
//  - a basis that lives on a lattice of directions (eigentransport, Haar:
//    native_directions()) takes the k lattice directions nearest to the
//    light's centre, each with I / k (the paper's nearest-direction rule);
//  - any other basis (SH) is evaluated at the exact direction.
// Brute-force re-projection, the reference of Fig. 7, resamples the cap per
// vertex and projects it into the basis.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/ground_truth.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Basis;
class Progress;

struct PointLight {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d colour = Eigen::Vector3d::Ones();
  double intensity = 1;
  double radius = 0;  // 0: an ideal point
  Eigen::Vector3d power() const { return intensity * colour; }
};

class PointLightProjector {
 public:
  enum class Rule { nearest, exact, brute_force };
  // The basis's own rule: nearest lattice directions (k = `nearest`) for a
  // basis with native directions, the exact direction otherwise.
  PointLightProjector(const Basis& basis, int nearest);
  // Per-vertex re-projection of each light's cap, sampled by `cap_samples`
  // directions (one when the radius is 0).
  static PointLightProjector brute_force(const Basis& basis, int cap_samples);

  Rule rule() const { return rule_; }
  // One line for logs: which rule, which lattice, which k.
  std::string describe() const;
  // Light vectors of unit power (v x n) of one light at every vertex.
  Eigen::MatrixXd light_vectors(const Mesh& mesh, const PointLight& light) const;

 private:
  PointLightProjector(const Basis& basis) : basis_(&basis) {}
  const Basis* basis_;
  Rule rule_ = Rule::exact;
  int nearest_ = 1, cap_samples_ = 1;
  std::optional<DirectionSet> lattice_;
};

// Exit radiance (v x 3, albedo 1) from the lights: t_p . l_p per vertex, with
// t_p decoded from the compressed transfer vertex by vertex; glossy transfer
// (rows > 1) is then read toward the camera through `exit_values` (v x rows).
Eigen::MatrixX3f point_light_radiance(const Mesh& mesh, const CompressedTransfer& transfer,
                                      int rows, const PointLightProjector& projector,
                                      const std::vector<PointLight>& lights,
                                      const MatrixXfRow* exit_values = nullptr);

// The ground truth (v x 3, albedo 1): per vertex and light, `samples`
// stratified directions uniform over the cap (one ray for radius 0), each
// traced only up to the light; `reflectance` (optional) as in
// ground_truth_radiance.
Eigen::MatrixX3f ground_truth_point_lights(const Mesh& mesh, const std::vector<PointLight>& lights,
                                           int samples, std::uint64_t seed,
                                           const Reflectance& reflectance = nullptr,
                                           Progress* progress = nullptr);

}  // namespace prt
