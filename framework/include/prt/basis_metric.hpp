// The metric of a basis: its Gram matrix G_ij = int B_i B_j over its domain.
//
// Coefficients in PRT are always a function's least-squares coefficients
// (f ~ sum_i c_i B_i): Basis::projection_matrix gives them (by default
// W E G^-1, which is W E for an orthonormal basis), rotation acts on them and
// a light reconstructed from them is the band-limited light. The integral of
// two functions is then t^T G l, so relighting applies G to the light before
// the transfer's dot products; for an orthonormal basis G = I and nothing is
// applied (docs/bases.md, "The metric of a basis").
#pragma once
#include <Eigen/Core>
#include <string>

#include "prt/direction_set.hpp"

namespace prt {

class Basis;

// The rule the metric is computed on: the basis's native_directions() when it
// has them (its own exact rule), otherwise a Gauss product rule exact for
// spherical polynomials of degree < 128 (the conformance kit's rule), over the
// upper hemisphere for a hemisphere basis.
DirectionSet metric_rule(const Basis& basis);

// G on metric_rule (n x n, symmetric), whatever orthonormal() claims.
Eigen::MatrixXd gram_matrix(const Basis& basis);

struct BasisMetric {
  bool identity = true;     // orthonormal(): G = I, nothing applied
  Eigen::MatrixXd gram;     // G (empty when identity)
  Eigen::MatrixXd inverse;  // G^-1, eigenvalues below cutoff x the largest discarded
  double condition = 1;     // largest / smallest kept eigenvalue
  int discarded = 0;        // eigenvalues discarded by the cut-off
};

// The relative cut-off below which G's eigenvalues are discarded (as the
// hemispherical SH least squares does), and the condition number above which
// a warning says that relighting loses digits.
inline constexpr double kMetricCutoff = 1e-10;
inline constexpr double kMetricWarnCondition = 1e8;

// The metric of a basis that is not orthonormal (identity otherwise). Warns
// once per basis description when G is ill-conditioned or rank-deficient.
BasisMetric basis_metric(const Basis& basis, double cutoff = kMetricCutoff);

}  // namespace prt
