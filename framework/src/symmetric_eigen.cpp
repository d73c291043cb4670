#include "prt/symmetric_eigen.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstddef>
#include <vector>

// LAPACK (Fortran ABI: arguments by reference, hidden string lengths last).
extern "C" void dstemr_(const char* jobz, const char* range, const int* n, double* d, double* e,
                        const double* vl, const double* vu, const int* il, const int* iu, int* m,
                        double* w, double* z, const int* ldz, const int* nzc, int* isuppz,
                        int* tryrac, double* work, const int* lwork, int* iwork, const int* liwork,
                        int* info, std::size_t jobz_length, std::size_t range_length);
extern "C" void dsterf_(const int* n, double* d, double* e, int* info);
extern "C" void dstein_(const int* n, const double* d, const double* e, const int* m,
                        const double* w, const int* iblock, const int* isplit, double* z,
                        const int* ldz, double* work, int* iwork, int* ifail, int* info);

namespace prt {

namespace {

// Eigen's full solver: the last fallback, when LAPACK reports a failure.
Eigenpairs full_solve(const Eigen::MatrixXd& a, Eigen::Index count) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(a);
  Eigenpairs out;
  if (solver.info() != Eigen::Success) return out;
  out.values = solver.eigenvalues().tail(count).reverse();
  out.vectors = solver.eigenvectors().rightCols(count).rowwise().reverse();
  return out;
}

// The wanted pairs of the tridiagonal (d, e) by MRRR (dstemr): the last
// `wanted` of n, ascending. False when LAPACK reports a failure.
bool pairs_by_mrrr(Eigen::VectorXd d, Eigen::VectorXd e, int wanted, Eigen::VectorXd& w,
                   Eigen::MatrixXd& z) {
  const int size = static_cast<int>(d.size());
  const int first = size - wanted + 1, last = size;  // 1-based, ascending order
  const double unused = 0;
  int found = 0, info = 0, tryrac = 1;
  w.resize(size);
  z.resize(size, wanted);
  std::vector<int> support(std::size_t(2 * wanted));
  double work_size = 0;
  int iwork_size = 0, query = -1;
  dstemr_("V", "I", &size, d.data(), e.data(), &unused, &unused, &first, &last, &found, w.data(),
          z.data(), &size, &wanted, support.data(), &tryrac, &work_size, &query, &iwork_size,
          &query, &info, 1, 1);
  if (info != 0) return false;
  const int lwork = static_cast<int>(work_size), liwork = iwork_size;
  std::vector<double> work(std::size_t(std::max(1, lwork)));
  std::vector<int> iwork(std::size_t(std::max(1, liwork)));
  tryrac = 1;
  dstemr_("V", "I", &size, d.data(), e.data(), &unused, &unused, &first, &last, &found, w.data(),
          z.data(), &size, &wanted, support.data(), &tryrac, work.data(), &lwork, iwork.data(),
          &liwork, &info, 1, 1);
  w.conservativeResize(wanted);
  return info == 0 && found == wanted;
}

// The same from every eigenvalue (dsterf, O(n^2) without vectors) and inverse
// iteration for the wanted vectors (dstein). MRRR's cost grows by ~0.2 n us
// per pair on this machine kind, dsterf's is ~0.007 n^2 us in all: the
// cheaper when many pairs of a small matrix are wanted.
bool pairs_by_inverse_iteration(const Eigen::VectorXd& d, const Eigen::VectorXd& e, int wanted,
                                Eigen::VectorXd& w, Eigen::MatrixXd& z) {
  const int size = static_cast<int>(d.size());
  Eigen::VectorXd values = d, off = e;
  int info = 0;
  dsterf_(&size, values.data(), off.data(), &info);  // ascending
  if (info != 0) return false;
  w = values.tail(wanted);
  z.resize(size, wanted);
  // One block: inverse iteration on the whole matrix, whatever its splits.
  std::vector<int> block(std::size_t(wanted), 1), split(1, size);
  std::vector<int> iwork(std::size_t(3 * size)), failed(static_cast<std::size_t>(wanted));
  std::vector<double> work(std::size_t(5 * size));
  dstein_(&size, d.data(), e.data(), &wanted, w.data(), block.data(), split.data(), z.data(), &size,
          work.data(), iwork.data(), failed.data(), &info);
  return info == 0;
}

// Q z for Q = H_0 ... H_{n-2}, the tridiagonalisation's reflectors, one
// reflector at a time: for a few columns this is 3-8x faster than Eigen's
// blocked product with the Householder sequence (which forms its block
// factors for all n - 1 reflectors).
void apply_q(const Eigen::Tridiagonalization<Eigen::MatrixXd>& t, Eigen::MatrixXd& z) {
  const Eigen::MatrixXd& packed = t.packedMatrix();
  const Eigen::VectorXd& tau = t.householderCoefficients();
  const Eigen::Index n = packed.rows();
  // Reflector i acts on rows i + 1.. with vector [1, packed(i + 2.., i)].
  for (Eigen::Index i = n - 2; i >= 0; --i) {
    if (tau[i] == 0) continue;
    const auto essential = packed.col(i).tail(n - i - 2);
    for (Eigen::Index c = 0; c < z.cols(); ++c) {
      auto tail = z.col(c).tail(n - i - 2);
      const double s = tau[i] * (z(i + 1, c) + essential.dot(tail));
      z(i + 1, c) -= s;
      tail -= s * essential;
    }
  }
}

}  // namespace

Eigenpairs largest_eigenpairs(const Eigen::MatrixXd& a, Eigen::Index count) {
  const Eigen::Index n = a.rows();
  count = std::clamp<Eigen::Index>(count, 0, n);
  Eigenpairs out;
  if (count == 0 || !a.allFinite()) return out;
  // Scaled to unit magnitude, as Eigen's solver does, away from over/underflow.
  const double scale = a.cwiseAbs().maxCoeff();
  if (!(scale > 0)) {
    out.values = Eigen::VectorXd::Zero(count);
    out.vectors = Eigen::MatrixXd::Identity(n, count);
    return out;
  }
  // LAPACK 3.11's dstemr orders the pair of a 2 x 2 matrix by magnitude
  // (Reference-LAPACK issue 826, fixed in 3.12): tiny sizes go to Eigen.
  if (n <= 2) return full_solve(a, count);
  Eigen::MatrixXd scaled = a / scale;
  const Eigen::Tridiagonalization<Eigen::MatrixXd> tridiagonal(scaled);
  const Eigen::VectorXd d = tridiagonal.diagonal();
  Eigen::VectorXd e(n);
  e.head(n - 1) = tridiagonal.subDiagonal();
  e[n - 1] = 0;
  const int wanted = static_cast<int>(count);
  Eigen::VectorXd w;
  Eigen::MatrixXd z;
  // The choice depends on the sizes only: the same input takes the same path.
  const bool many = n <= 16 * count;
  const bool solved =
      (many && pairs_by_inverse_iteration(d, e, wanted, w, z)) || pairs_by_mrrr(d, e, wanted, w, z);
  if (!solved) return full_solve(a, count);
  apply_q(tridiagonal, z);
  // Ascending from LAPACK: the largest first.
  out.values = (w * scale).reverse();
  out.vectors = z.rowwise().reverse();
  return out;
}

}  // namespace prt
