// Spherical harmonics restricted to the upper hemisphere (z > 0 in the local
// frame), after Sloan et al. 2003 §3.2 and the Appendix: the Gram matrix
// A_ik = int_H y_i y_k, the least-squares projection c = A^-1 b, and the
// zero-hemisphere and odd/even-reflection projections it is compared with.
// Everything is integrated exactly: SH restricted to H are polynomials, so
// Gauss-Legendre in z on [0, 1] times uniform phi is exact.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "prt/direction_set.hpp"

namespace prt::hemisphere {

// Exact quadrature over the upper hemisphere for polynomials of degree < 2n.
DirectionSet upper_quadrature(int n);

// A_ik = int_H y_i y_k for SH of orders `rows` x `cols` (order^2 each).
Eigen::MatrixXd gram(int rows_order, int cols_order);
inline Eigen::MatrixXd gram(int order) {
  return gram(order, order);
}

// The least-squares inverse of A through its SVD: singular values below
// `relative_cutoff` x the largest are discarded (their inverses set to 0).
// Optionally drops one basis function first (e.g. the nearly redundant
// l = 1, m = 0 at index 2), giving N - 1 functions.
struct LeastSquares {
  Eigen::MatrixXd gram;             // A of the kept functions
  Eigen::MatrixXd inverse;          // pseudo-inverse of A with the cut-off
  Eigen::VectorXd singular_values;  // of A, descending
  std::vector<int> kept;            // SH indices of the kept functions
  int discarded = 0;                // singular values below the cut-off
};
LeastSquares least_squares(int order, double relative_cutoff, int dropped_index = -1);

// Residual of each basis function against the span of the others over H:
// min_c int_H (y_i - sum_{k != i} c_k y_k)^2 = 1 / (A^-1)_ii.
Eigen::VectorXd redundancy_residuals(const Eigen::MatrixXd& gram);

// Error of a projection over H for every unit-power signal f = sum a_i y_i of
// the order-N space (|a| = 1): a^T E a with E symmetric. Worst case = largest
// eigenvalue of E, average over the unit sphere of a = trace(E) / N^2.
struct ErrorSummary {
  double worst = 0, average = 0;
};
ErrorSummary summarize(const Eigen::MatrixXd& error_form);

// Error forms of the projections of the order-N space:
Eigen::MatrixXd zero_hemisphere_error(int order);  // c = b (no correction)
Eigen::MatrixXd least_squares_error(int order, const LeastSquares& ls);
// Reflect f across z = 0 with odd (-f(x, y, -z)) or even (+) symmetry,
// project into SH of `reflection_order`, and compare with f over H.
Eigen::MatrixXd reflection_error(int order, int reflection_order, bool odd);

}  // namespace prt::hemisphere
