// Real spherical harmonics, shared by the SH basis plug-ins and renderers.
//
// Conventions (pinned by tests against closed forms):
//  - index i = l (l + 1) + m, l = 0..order-1 ("order" counts bands: order^2
//    coefficients);
//  - orthonormal over the sphere;
//  - NO Condon-Shortley phase: y_{1,-1} = c y, y_{1,0} = c z, y_{1,1} = c x with
//    c = sqrt(3 / 4 pi), so the l = 1 rotation block is the Cartesian rotation
//    in (y, z, x) order;
//  - y_{l,m} = sqrt(2) K_l^m P_l^|m|(z) cos(m phi) for m > 0 and
//    sqrt(2) K_l^|m| P_l^|m|(z) sin(|m| phi) for m < 0.
// Evaluation uses the normalised associated-Legendre recurrence with sin^m(theta)
// kept in the sectoral seeds and cos/sin(m phi) from (x, y) / sin(theta), so no
// factorials appear and nothing overflows (finite and accurate to l = 1600;
// seeds below the double range start to matter beyond l ~ 1800).
#pragma once
#include <Eigen/Core>
#include <string>

#include "prt/direction_set.hpp"

namespace prt::sh {

inline int index(int l, int m) {
  return l * (l + 1) + m;
}
inline int coefficient_count(int order) {
  return order * order;
}

// Writes the order^2 values at unit direction (x, y, z) into `out`.
void evaluate(int order, double x, double y, double z, double* out);

// s x order^2 matrix of values at the directions.
Eigen::MatrixXd evaluate(int order, const Directions& directions);

// Block-diagonal order^2 x order^2 matrix mapping the coefficients of f to
// those of g(d) = f(R^T d): Rotation(order, R).dense() (prt/sh_rotation.hpp,
// which also has the block-diagonal form, apply and single bands).
Eigen::MatrixXd rotation(int order, const Eigen::Matrix3d& rotation);

// Coefficients (order^2 x 3) of an equirectangular RGB image (width x height
// texels, row-major, rgb interleaved), each texel sampled at its centre and
// weighted by its exact solid angle (as DirectionSet::equirect), by a
// separable transform: Fourier sums per row, then Legendre per row.
Eigen::MatrixX3d project_equirect(int order, int width, int height, const float* rgb);

// Per-band sigma factors that damp Gibbs ringing of truncated SH (e.g. the
// negative lobes around a bright sun): "none" (1), "hanning"
// (0.5 (1 + cos(pi l / order))) or "lanczos" (sinc(l / order)); order^2 values,
// one per coefficient. Throws prt::Error for another name.
Eigen::VectorXd window(int order, const std::string& kind);

// Zonal coefficients z_l of the clamped cosine max(cos theta, 0) about +z.
Eigen::VectorXd clamped_cosine_zonal(int order);

// Coefficients of max(n . d, 0) for unit n (Funk-Hecke: sqrt(4 pi/(2l+1)) z_l y_lm(n)).
Eigen::VectorXd clamped_cosine(int order, const Eigen::Vector3d& normal);

}  // namespace prt::sh
