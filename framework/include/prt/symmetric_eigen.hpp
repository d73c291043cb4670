// The largest eigenpairs of a symmetric matrix, without the full
// decomposition: Householder tridiagonalisation (Eigen), then only the wanted
// eigenpairs of the tridiagonal matrix (LAPACK: MRRR, dstemr, for a few
// pairs; every eigenvalue by dsterf and inverse iteration, dstein, when many
// pairs of a small matrix are wanted), then the back-transform of those
// vectors, a reflector at a time. A full Eigen solve computes and
// accumulates every eigenvector, which dominates per-cluster PCA.
#pragma once
#include <Eigen/Core>
#include <vector>

namespace prt {

struct Eigenpairs {
  Eigen::VectorXd values;   // descending
  Eigen::MatrixXd vectors;  // one unit column per value
};

// The `count` largest eigenpairs of the symmetric matrix `a` (both triangles
// filled). Fewer when count > a.rows(); none when `a` is not
// finite. Deterministic: the same bits for the same input on any thread.
Eigenpairs largest_eigenpairs(const Eigen::MatrixXd& a, Eigen::Index count);

// The same for many matrices, eight at a time in the lanes of a vector
// (symmetric_eigen_batch.cpp): the same pairs to rounding, about twice as
// fast per matrix at n = 100. A batch pads its smaller matrices with zeros,
// which changes none of their bits: a matrix's result does not depend on the
// other matrices of the call, nor on their order. Those of size 3 to
// kLargestBatchedEigen with
// count <= size are batched; the others, and any that fails its check
// (residual and orthogonality), are solved by largest_eigenpairs. Throws on
// a matrix that is not square.
inline constexpr Eigen::Index kLargestBatchedEigen = 256;
std::vector<Eigenpairs> largest_eigenpairs_batch(
    const std::vector<const Eigen::MatrixXd*>& matrices, Eigen::Index count);

}  // namespace prt
