// The largest eigenpairs of many matrices, batched eight to a vector
// (largest_eigenpairs_batch) against one at a time (largest_eigenpairs), on
// one core: the time per matrix and the largest differences between the two.
//
//   bench_eigen_batch [n] [pairs] [rows] [decay]
//
// The matrices are scatters Y^T Y of `rows` random rows whose columns decay as
// decay^j, like a cluster's scatter in CPCA (n = 100: the bunny's diffuse
// rows). This is a measurement for docs/performance.md, with no limit of its
// own: the CPCA iteration rows of scripts/perf.sh hold the limit.
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "prt/symmetric_eigen.hpp"
#include "timing.hpp"

int main(int argc, char** argv) {
  const Eigen::Index n = argc > 1 ? std::stol(argv[1]) : 100;
  const Eigen::Index pairs = argc > 2 ? std::stol(argv[2]) : 9;
  const Eigen::Index rows = argc > 3 ? std::stol(argv[3]) : n + 50;
  const double decay = argc > 4 ? std::stod(argv[4]) : 0.9;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::vector<Eigen::MatrixXd> matrices(64);
  std::vector<const Eigen::MatrixXd*> pointers;
  for (Eigen::MatrixXd& a : matrices) {
    Eigen::MatrixXd y(rows, n);
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = 0; i < rows; ++i) y(i, j) = uniform(rng) * std::pow(decay, double(j));
    a = y.transpose() * y;
    pointers.push_back(&a);
  }
  std::vector<prt::Eigenpairs> single(matrices.size()), batched;
  const auto [one, eight] = prt::bench::alternating_median_seconds(
      5,
      [&] {
        for (std::size_t m = 0; m < matrices.size(); ++m)
          single[m] = prt::largest_eigenpairs(matrices[m], pairs);
      },
      [&] { batched = prt::largest_eigenpairs_batch(pointers, pairs); });
  double values = 0, residual = 0, orthogonality = 0;
  for (std::size_t m = 0; m < matrices.size(); ++m) {
    const prt::Eigenpairs& b = batched[m];
    const double top = single[m].values[0];
    values = std::max(values, (b.values - single[m].values).cwiseAbs().maxCoeff() / top);
    residual = std::max(
        residual,
        (matrices[m] * b.vectors - b.vectors * b.values.asDiagonal()).cwiseAbs().maxCoeff() / top);
    orthogonality = std::max(
        orthogonality, (b.vectors.transpose() * b.vectors - Eigen::MatrixXd::Identity(pairs, pairs))
                           .cwiseAbs()
                           .maxCoeff());
  }
  const double per = 1e6 / double(matrices.size());
  std::printf("n = %ld, %ld pairs, scatters of %ld rows (decay %g), 64 matrices, one core\n",
              long(n), long(pairs), long(rows), decay);
  std::printf("one at a time: %.1f us per matrix; batched: %.1f us per matrix (%.2fx)\n", one * per,
              eight * per, one / eight);
  std::printf(
      "batched against one at a time: eigenvalues within %.1e of the largest; residual "
      "%.1e, orthogonality %.1e\n",
      values, residual, orthogonality);
  return 0;
}
