#include "prt/hemisphere.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "prt/error.hpp"
#include "prt/quadrature.hpp"
#include "prt/sh.hpp"

namespace prt::hemisphere {

DirectionSet upper_quadrature(int n) {
  const GaussLegendre rule = gauss_legendre(n);
  const int m = 2 * n + 2;
  DirectionSet set{"gauss-hemisphere", Directions(n * m, 3), Eigen::VectorXd(n * m)};
  for (int i = 0; i < n; ++i) {
    const double z = 0.5 * (rule.nodes[i] + 1.0), r = std::sqrt(std::max(0.0, 1.0 - z * z));
    for (int j = 0; j < m; ++j) {
      const double phi = 2.0 * M_PI * (j + 0.5) / m;
      const int k = i * m + j;
      set.directions.row(k) << r * std::cos(phi), r * std::sin(phi), z;
      set.weights[k] = 0.5 * rule.weights[i] * 2.0 * M_PI / m;
    }
  }
  return set;
}

Eigen::MatrixXd gram(int rows_order, int cols_order) {
  const DirectionSet set = upper_quadrature(std::max(rows_order, cols_order) + 1);
  const Eigen::MatrixXd a = sh::evaluate(rows_order, set.directions);
  const Eigen::MatrixXd b = sh::evaluate(cols_order, set.directions);
  return a.transpose() * set.weights.asDiagonal() * b;
}

LeastSquares least_squares(int order, double relative_cutoff, int dropped_index) {
  const int n = order * order;
  if (dropped_index >= n) throw Error("least_squares: dropped index out of range");
  LeastSquares ls;
  for (int i = 0; i < n; ++i)
    if (i != dropped_index) ls.kept.push_back(i);
  const Eigen::MatrixXd full = gram(order);
  ls.gram.resize(ls.kept.size(), ls.kept.size());
  for (std::size_t i = 0; i < ls.kept.size(); ++i)
    for (std::size_t k = 0; k < ls.kept.size(); ++k) ls.gram(i, k) = full(ls.kept[i], ls.kept[k]);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(ls.gram, Eigen::ComputeFullU | Eigen::ComputeFullV);
  ls.singular_values = svd.singularValues();
  const double largest = ls.singular_values.size() ? ls.singular_values[0] : 0.0;
  Eigen::VectorXd inverted(ls.singular_values.size());
  for (Eigen::Index i = 0; i < inverted.size(); ++i) {
    const bool keep = ls.singular_values[i] > relative_cutoff * largest;
    inverted[i] = keep ? 1.0 / ls.singular_values[i] : 0.0;
    ls.discarded += !keep;
  }
  ls.inverse = svd.matrixV() * inverted.asDiagonal() * svd.matrixU().transpose();
  return ls;
}

Eigen::VectorXd redundancy_residuals(const Eigen::MatrixXd& gram) {
  const Eigen::MatrixXd inverse = gram.inverse();  // analysis only: A is invertible for N <= 10
  return inverse.diagonal().cwiseInverse();
}

ErrorSummary summarize(const Eigen::MatrixXd& e) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(0.5 * (e + e.transpose()));
  // Exact projections give zero; rounding must not print as a negative error.
  return {std::max(0.0, solver.eigenvalues().maxCoeff()),
          std::max(0.0, e.trace() / double(e.rows()))};
}

namespace {
// int_H (f - g)^2 for f = y . a (order N) and g = y' . (P a) (order M):
// a^T (A_NN - P^T A_MN - A_NM P + P^T A_MM P) a.
Eigen::MatrixXd error_form(int order, int reconstruction_order, const Eigen::MatrixXd& p) {
  const Eigen::MatrixXd ann = gram(order, order),
                        amm = gram(reconstruction_order, reconstruction_order);
  const Eigen::MatrixXd amn = gram(reconstruction_order, order);
  return ann - p.transpose() * amn - amn.transpose() * p + p.transpose() * amm * p;
}
}  // namespace

Eigen::MatrixXd zero_hemisphere_error(int order) {
  return error_form(order, order, gram(order));
}

Eigen::MatrixXd least_squares_error(int order, const LeastSquares& ls) {
  // Coefficients of the kept functions: A_kept^+ b_kept, b = A_full a.
  const int n = order * order;
  const Eigen::MatrixXd full = gram(order);
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd b_kept(ls.kept.size(), n);
  for (std::size_t i = 0; i < ls.kept.size(); ++i) b_kept.row(i) = full.row(ls.kept[i]);
  const Eigen::MatrixXd c = ls.inverse * b_kept;
  for (std::size_t i = 0; i < ls.kept.size(); ++i) p.row(ls.kept[i]) = c.row(i);
  return error_form(order, order, p);
}

Eigen::MatrixXd reflection_error(int order, int reflection_order, bool odd) {
  // Projection of the reflected f onto y_j (order M): y_j(x, y, -z) =
  // (-1)^(l+m) y_j(x, y, z), so c_j = (1 +- (-1)^(l+m)) int_H f y_j.
  const Eigen::MatrixXd amn = gram(reflection_order, order);
  Eigen::MatrixXd p = amn;
  for (int l = 0; l < reflection_order; ++l)
    for (int m = -l; m <= l; ++m) {
      const double parity = ((l + m) % 2 == 0) ? 1.0 : -1.0;
      p.row(sh::index(l, m)) *= odd ? 1.0 - parity : 1.0 + parity;
    }
  return error_form(order, reflection_order, p);
}

}  // namespace prt::hemisphere
