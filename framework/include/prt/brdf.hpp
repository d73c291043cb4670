// Reflectance models for glossy transfer (Sloan 2003 §3.1, Chen 2005 §3.1):
// Lambert, normalised Phong, anisotropic Ward and Cook-Torrance, each a
// diffuse part kd / pi plus a specular lobe scaled by ks. Directions are unit
// vectors in the local frame (z = normal, x = tangent); both point away from
// the surface.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "prt/direction_set.hpp"

namespace prt {

class Params;

enum class BrdfModel { lambert, phong, ward, cook_torrance };
// The model named as in a scene ("lambert", "phong", "ward", "cook-torrance");
// throws prt::Error for any other name.
BrdfModel brdf_model(const std::string& name);

struct Brdf {
  BrdfModel model = BrdfModel::lambert;
  double kd = 1.0;                      // diffuse weight
  double ks = 0.0;                      // specular weight
  double exponent = 32;                 // Phong
  double alpha_x = 0.2, alpha_y = 0.2;  // Ward roughness along tangent / bitangent
  double roughness = 0.3;               // Cook-Torrance Beckmann slope
  double f0 = 0.04;                     // Cook-Torrance Schlick reflectance at normal incidence

  bool glossy() const { return model != BrdfModel::lambert; }

  // rho(in, out); zero when either direction is below the horizon.
  double evaluate(const Eigen::Vector3d& in, const Eigen::Vector3d& out) const;
  std::string describe() const;
};

// The BRDF convolved with SH of `incident_order` over the local hemisphere,
// at each exit direction v (rows of `exit_directions`):
//   F(v, j) = int_H rho(s, v) y_j(s) s_z ds     (q x incident_order^2)
// integrated by the Gauss product rule upper_quadrature(resolution).
Eigen::MatrixXd brdf_incident_integrals(const Brdf& brdf, const Directions& exit_directions,
                                        int incident_order, int resolution = 48);

// The BRDF matrix of Sloan 2003 §3.1 in SH over the local hemisphere:
//   B_ij = int_H int_H y_i(v) y_j(s) rho(v, s) s_z ds dv
// rows: SH of `exit_order` restricted to the indices `exit_kept`; columns: all
// order^2 SH of `light_order`. Integrated by a Gauss product rule with
// `resolution` nodes in cos(theta) (and 2x that in phi) per hemisphere.
Eigen::MatrixXd brdf_matrix(const Brdf& brdf, int exit_order, const std::vector<int>& exit_kept,
                            int light_order, int resolution = 48);

}  // namespace prt
