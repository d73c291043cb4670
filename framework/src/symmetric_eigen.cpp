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

namespace prt {

namespace {

// Eigen's full solver: the fallback when MRRR reports a failure.
Eigenpairs full_solve(const Eigen::MatrixXd& a, Eigen::Index count) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(a);
  Eigenpairs out;
  if (solver.info() != Eigen::Success) return out;
  out.values = solver.eigenvalues().tail(count).reverse();
  out.vectors = solver.eigenvectors().rightCols(count).rowwise().reverse();
  return out;
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
  Eigen::VectorXd d = tridiagonal.diagonal();
  Eigen::VectorXd e(n);
  e.head(n - 1) = tridiagonal.subDiagonal();
  e[n - 1] = 0;
  const int size = static_cast<int>(n), wanted = static_cast<int>(count);
  const int first = size - wanted + 1, last = size;  // 1-based, ascending order
  const double unused = 0;
  int found = 0, info = 0, tryrac = 1;
  Eigen::VectorXd w(n);
  Eigen::MatrixXd z(n, count);
  std::vector<int> support(std::size_t(2 * wanted));
  double work_size = 0;
  int iwork_size = 0, query = -1;
  dstemr_("V", "I", &size, d.data(), e.data(), &unused, &unused, &first, &last, &found, w.data(),
          z.data(), &size, &wanted, support.data(), &tryrac, &work_size, &query, &iwork_size,
          &query, &info, 1, 1);
  if (info != 0) return full_solve(a, count);
  const int lwork = static_cast<int>(work_size), liwork = iwork_size;
  std::vector<double> work(std::size_t(std::max(1, lwork)));
  std::vector<int> iwork(std::size_t(std::max(1, liwork)));
  tryrac = 1;
  dstemr_("V", "I", &size, d.data(), e.data(), &unused, &unused, &first, &last, &found, w.data(),
          z.data(), &size, &wanted, support.data(), &tryrac, work.data(), &lwork, iwork.data(),
          &liwork, &info, 1, 1);
  if (info != 0 || found != wanted) return full_solve(a, count);
  // Ascending from dstemr: the largest first.
  out.values = (w.head(count) * scale).reverse();
  out.vectors = (tridiagonal.matrixQ() * z).rowwise().reverse();
  return out;
}

}  // namespace prt
