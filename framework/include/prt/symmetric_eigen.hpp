// The largest eigenpairs of a symmetric matrix, without the full
// decomposition: Householder tridiagonalisation (Eigen), then only the wanted
// eigenpairs of the tridiagonal matrix (LAPACK: MRRR, dstemr, for a few
// pairs; every eigenvalue by dsterf and inverse iteration, dstein, when many
// pairs of a small matrix are wanted), then the back-transform of those
// vectors, a reflector at a time. A full Eigen solve computes and
// accumulates every eigenvector, which dominates per-cluster PCA.
#pragma once
#include <Eigen/Core>

namespace prt {

struct Eigenpairs {
  Eigen::VectorXd values;   // descending
  Eigen::MatrixXd vectors;  // one unit column per value
};

// The `count` largest eigenpairs of the symmetric matrix `a` (both triangles
// filled). Fewer when count > a.rows(); none when `a` is not
// finite. Deterministic: the same bits for the same input on any thread.
Eigenpairs largest_eigenpairs(const Eigen::MatrixXd& a, Eigen::Index count);

}  // namespace prt
