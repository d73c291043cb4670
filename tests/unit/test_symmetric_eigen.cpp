#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

#include "prt/symmetric_eigen.hpp"

using prt::Eigenpairs;
using prt::largest_eigenpairs;

namespace {
Eigen::MatrixXd random_psd(Eigen::Index n, Eigen::Index rank, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd y(n, rank);
  for (auto& v : y.reshaped()) v = g(rng);
  return y * y.transpose();
}

// A v = lambda v and V^T V = I, relative to the largest eigenvalue.
void check_pairs(const Eigen::MatrixXd& a, const Eigenpairs& pairs, double tolerance) {
  const double top = std::max(1e-300, std::abs(pairs.values[0]));
  CHECK((a * pairs.vectors - pairs.vectors * pairs.values.asDiagonal()).cwiseAbs().maxCoeff() /
            top <
        tolerance);
  const Eigen::MatrixXd gram = pairs.vectors.transpose() * pairs.vectors;
  CHECK((gram - Eigen::MatrixXd::Identity(gram.rows(), gram.cols())).cwiseAbs().maxCoeff() <
        tolerance);
  for (Eigen::Index i = 1; i < pairs.values.size(); ++i)
    CHECK(pairs.values[i] <= pairs.values[i - 1]);
}

// Eigenvalues 3, 3(1 + 1e-13), 3(1 - 1e-13), 3 and the rest spread in
// [0, 1]; q's first four columns span the cluster's space.
struct Clustered {
  Eigen::MatrixXd a, q;
};
Clustered clustered(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd random(n, n);
  for (auto& v : random.reshaped()) v = g(rng);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(random).householderQ();
  Eigen::VectorXd spectrum = Eigen::VectorXd::LinSpaced(n, 0.0, 1.0);
  spectrum.head(4) << 3, 3 * (1 + 1e-13), 3 * (1 - 1e-13), 3;
  const Eigen::MatrixXd a = q * spectrum.asDiagonal() * q.transpose();
  return {0.5 * (a + a.transpose()), q};
}
}  // namespace

TEST_CASE("largest eigenpairs equal the full solver's", "[eigen][extremes]") {
  for (Eigen::Index n : {2, 3, 17, 100, 240}) {
    const Eigen::MatrixXd a = random_psd(n, n + 3, std::uint64_t(n));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> full(a);
    for (Eigen::Index count : {Eigen::Index(1), std::min<Eigen::Index>(9, n), n}) {
      INFO("n " << n << ", count " << count);
      const Eigenpairs pairs = largest_eigenpairs(a, count);
      REQUIRE(pairs.values.size() == count);
      REQUIRE(pairs.vectors.cols() == count);
      for (Eigen::Index i = 0; i < count; ++i) {
        const double expected = full.eigenvalues()[n - 1 - i];
        CHECK(pairs.values[i] ==
              Approx(expected).epsilon(1e-12).margin(1e-12 * full.eigenvalues()[n - 1]));
      }
      check_pairs(a, pairs, 1e-12);
      // Well-separated vectors agree with the full solver's up to sign.
      const double gap = full.eigenvalues()[n - 1] - full.eigenvalues()[n - 2];
      if (gap > 1e-3 * full.eigenvalues()[n - 1])
        CHECK(std::abs(pairs.vectors.col(0).dot(full.eigenvectors().col(n - 1))) ==
              Approx(1.0).epsilon(1e-10));
    }
  }
}

TEST_CASE("largest eigenpairs at the extremes", "[eigen][extremes]") {
  // Rank-deficient: the largest pairs are exact, the rest are zero.
  const Eigen::MatrixXd low = random_psd(60, 4, 7);
  const Eigenpairs pairs = largest_eigenpairs(low, 8);
  REQUIRE(pairs.values.size() == 8);
  check_pairs(low, pairs, 1e-12);
  CHECK(std::abs(pairs.values[5]) < 1e-12 * pairs.values[0]);
  // Repeated eigenvalues (identity): any orthonormal vectors, unit values.
  const Eigenpairs identity = largest_eigenpairs(Eigen::MatrixXd::Identity(30, 30), 5);
  check_pairs(Eigen::MatrixXd::Identity(30, 30), identity, 1e-12);
  CHECK((identity.values.array() - 1).abs().maxCoeff() < 1e-14);
  // Magnitudes near the ends of the double range keep their relative accuracy.
  for (double scale : {1e-300, 1e-150, 1e150, 1e300}) {
    INFO("scale " << scale);
    const Eigen::MatrixXd base = random_psd(40, 40, 11);
    const Eigen::MatrixXd a = base * (scale / base.cwiseAbs().maxCoeff());
    const Eigenpairs p = largest_eigenpairs(a, 3);
    REQUIRE(p.values.size() == 3);
    CHECK(p.values.allFinite());
    CHECK(p.vectors.allFinite());
    check_pairs(a, p, 1e-12);
  }
  // Zero, 1 x 1, empty, count beyond n, count zero, non-finite.
  const Eigenpairs zero = largest_eigenpairs(Eigen::MatrixXd::Zero(5, 5), 2);
  CHECK(zero.values == Eigen::VectorXd::Zero(2));
  CHECK(zero.vectors.allFinite());
  const Eigenpairs one = largest_eigenpairs(Eigen::MatrixXd::Constant(1, 1, -2.5), 4);
  REQUIRE(one.values.size() == 1);
  CHECK(one.values[0] == -2.5);
  CHECK(largest_eigenpairs(Eigen::MatrixXd(0, 0), 3).values.size() == 0);
  CHECK(largest_eigenpairs(random_psd(6, 6, 1), 0).values.size() == 0);
  CHECK(largest_eigenpairs(random_psd(6, 6, 1), 10).values.size() == 6);
  Eigen::MatrixXd bad = random_psd(6, 6, 2);
  bad(2, 3) = bad(3, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK(largest_eigenpairs(bad, 2).values.size() == 0);
  bad(2, 3) = bad(3, 2) = std::numeric_limits<double>::infinity();
  CHECK(largest_eigenpairs(bad, 2).values.size() == 0);
  // Indefinite: the largest (most positive) first.
  Eigen::MatrixXd indefinite = Eigen::MatrixXd::Zero(3, 3);
  indefinite.diagonal() << -5, 1, 3;
  const Eigenpairs signs = largest_eigenpairs(indefinite, 2);
  CHECK(signs.values[0] == Approx(3));
  CHECK(signs.values[1] == Approx(1));
  // 2 x 2 with the negative eigenvalue the larger in magnitude (LAPACK 3.11's
  // dstemr ordered this pair by magnitude).
  Eigen::Matrix2d pair;
  pair << -5, 0.5, 0.5, 1;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> exact{Eigen::MatrixXd(pair)};
  const Eigenpairs top = largest_eigenpairs(pair, 1);
  REQUIRE(top.values.size() == 1);
  CHECK(top.values[0] == Approx(exact.eigenvalues()[1]));
  const Eigenpairs both = largest_eigenpairs(pair, 2);
  CHECK(both.values[0] == Approx(exact.eigenvalues()[1]));
  CHECK(both.values[1] == Approx(exact.eigenvalues()[0]));
  check_pairs(pair, both, 1e-12);
}

TEST_CASE("largest eigenpairs with clustered eigenvalues, on either tridiagonal solver",
          "[eigen][extremes]") {
  // Eigenvalues equal to 1e-13 apart: inverse iteration must reorthogonalise
  // within the cluster, MRRR must separate it. n <= 16 count takes the first
  // (many pairs of a small matrix), n > 16 count the second.
  for (const auto& [n, count] : {std::pair<Eigen::Index, Eigen::Index>{40, 8}, {200, 3}}) {
    INFO("n " << n << ", count " << count);
    const auto [a, q] = clustered(n, std::uint64_t(5 + n));
    const Eigenpairs pairs = largest_eigenpairs(a, count);
    REQUIRE(pairs.values.size() == count);
    check_pairs(a, pairs, 1e-12);
    for (Eigen::Index i = 0; i < std::min<Eigen::Index>(count, 4); ++i)
      CHECK(pairs.values[i] == Approx(3).epsilon(1e-12));
    // The cluster's vectors span the cluster's space: Q's first four columns.
    const Eigen::MatrixXd in_space =
        q.leftCols(4).transpose() * pairs.vectors.leftCols(std::min<Eigen::Index>(count, 4));
    CHECK((in_space.colwise().norm().array() - 1).abs().maxCoeff() < 1e-10);
  }
}

TEST_CASE("batched largest eigenpairs agree with the single solver's", "[eigen][extremes]") {
  std::vector<Eigen::MatrixXd> matrices;
  for (Eigen::Index n : {3, 9, 17, 60, 100, 101, 150, 192, 240})
    matrices.push_back(random_psd(n, n + 3, std::uint64_t(100 + n)));
  matrices.push_back(random_psd(60, 4, 7));  // rank 4
  matrices.push_back(Eigen::MatrixXd::Identity(30, 30));
  matrices.push_back(clustered(40, 5).a);
  Eigen::MatrixXd indefinite = Eigen::MatrixXd::Zero(3, 3);
  indefinite.diagonal() << -5, 1, 3;
  matrices.push_back(indefinite);
  for (double scale : {1e-300, 1e300}) {
    const Eigen::MatrixXd base = random_psd(40, 40, 11);
    matrices.push_back(base * (scale / base.cwiseAbs().maxCoeff()));
  }
  matrices.push_back(Eigen::MatrixXd::Zero(12, 12));
  Eigen::MatrixXd bad = random_psd(12, 12, 2);
  bad(2, 3) = bad(3, 2) = std::numeric_limits<double>::quiet_NaN();
  matrices.push_back(bad);
  std::vector<const Eigen::MatrixXd*> pointers;
  for (const auto& m : matrices) pointers.push_back(&m);
  for (Eigen::Index count : {1, 3, 9}) {
    const std::vector<Eigenpairs> batch = prt::largest_eigenpairs_batch(pointers, count);
    REQUIRE(batch.size() == matrices.size());
    for (std::size_t i = 0; i < matrices.size(); ++i) {
      INFO("matrix " << i << " (" << matrices[i].rows() << " rows), count " << count);
      const Eigenpairs single = largest_eigenpairs(matrices[i], count);
      REQUIRE(batch[i].values.size() == single.values.size());
      if (single.values.size() == 0) continue;  // not finite: none, as the single solver
      REQUIRE(batch[i].vectors.rows() == matrices[i].rows());
      const double top = std::max(std::abs(single.values[0]), 1e-300);
      CHECK((batch[i].values - single.values).cwiseAbs().maxCoeff() <= 1e-12 * top);
      if (single.values[0] != 0) check_pairs(matrices[i], batch[i], 1e-12);
      CHECK(batch[i].vectors.allFinite());
    }
  }
}

TEST_CASE("a batched matrix's pairs do not depend on its batch", "[eigen]") {
  // Alone, among larger matrices (padded to their size), and in another
  // order: the same bits.
  const Eigen::MatrixXd own = random_psd(57, 80, 3);
  const Eigen::MatrixXd larger = random_psd(100, 120, 4), other = clustered(90, 6).a;
  const Eigenpairs alone = prt::largest_eigenpairs_batch({&own}, 9).front();
  const std::vector<Eigenpairs> mixed =
      prt::largest_eigenpairs_batch({&larger, &own, &other, &larger, &own}, 9);
  const std::vector<Eigenpairs> reversed =
      prt::largest_eigenpairs_batch({&own, &larger, &other, &own, &larger}, 9);
  for (const Eigenpairs* p : {&mixed[1], &mixed[4], &reversed[0], &reversed[3]}) {
    CHECK(p->values == alone.values);
    CHECK(p->vectors == alone.vectors);
  }
  CHECK(mixed[0].values == reversed[1].values);
  CHECK(mixed[0].vectors == reversed[1].vectors);
  check_pairs(own, alone, 1e-12);
  const Eigen::MatrixXd wide = Eigen::MatrixXd::Zero(3, 4);
  CHECK_THROWS_WITH(prt::largest_eigenpairs_batch({&wide}, 1), Catch::Contains("not square"));
}
