#include <catch2/catch.hpp>

#include "prt/hemisphere.hpp"
#include "prt/sh.hpp"

using namespace prt;

TEST_CASE("the hemispherical Gram matrix matches Sloan 2003 §9.1", "[hemisphere]") {
  const auto ls = hemisphere::least_squares(5, 1e-10);
  const Eigen::VectorXd& s = ls.singular_values;
  CHECK(s[0] == Approx(1.0).epsilon(1e-4));
  CHECK(s[24] == Approx(6.59e-6).epsilon(1e-3));  // "6.59 x 10^-6"
  CHECK(s[23] == Approx(3.10e-4).epsilon(2e-3));  // "3.10 x 10^-4"
  CHECK(ls.discarded == 0);
  // A restricted to H is symmetric and its trace is half the sphere's.
  CHECK((ls.gram - ls.gram.transpose()).cwiseAbs().maxCoeff() < 1e-14);
  CHECK(ls.gram.trace() == Approx(12.5).epsilon(1e-12));
  // The l = 1, m = 0 function is the most redundant, residual 1.48e-5.
  const Eigen::VectorXd r = hemisphere::redundancy_residuals(ls.gram);
  Eigen::Index most;
  r.minCoeff(&most);
  CHECK(most == sh::index(1, 0));
  CHECK(r[most] == Approx(1.48e-5).epsilon(3e-3));
}

TEST_CASE("projection errors match Sloan 2003 §9 to the printed digits", "[hemisphere]") {
  const auto zero = hemisphere::summarize(hemisphere::zero_hemisphere_error(5));
  CHECK(zero.worst == Approx(0.125).margin(5e-4));
  CHECK(zero.average == Approx(0.0402).margin(5e-5));
  const auto odd8 = hemisphere::summarize(hemisphere::reflection_error(5, 8, true));
  CHECK(odd8.worst == Approx(0.145).margin(5e-4));
  CHECK(odd8.average == Approx(0.044).margin(5e-4));
  const auto even7 = hemisphere::summarize(hemisphere::reflection_error(5, 7, false));
  CHECK(even7.worst == Approx(0.022).margin(5e-4));
  CHECK(even7.average == Approx(0.0036).margin(5e-5));
  const auto even5 = hemisphere::summarize(hemisphere::reflection_error(5, 5, false));
  CHECK(even5.worst == Approx(0.193).margin(5e-4));
  CHECK(even5.average == Approx(0.030).margin(5e-4));
}

TEST_CASE("least squares reproduces the order-N space exactly over H", "[hemisphere]") {
  for (int order : {1, 2, 5, 8}) {
    const auto ls = hemisphere::least_squares(order, 1e-12);
    const auto e = hemisphere::summarize(hemisphere::least_squares_error(order, ls));
    INFO("order " << order);
    CHECK(e.worst < 1e-8);
  }
  // Dropping the redundant function costs exactly its residual in the worst case.
  const auto reduced = hemisphere::least_squares(5, 1e-10, sh::index(1, 0));
  CHECK(reduced.kept.size() == 24);
  const auto e = hemisphere::summarize(hemisphere::least_squares_error(5, reduced));
  CHECK(e.worst == Approx(1.48e-5).epsilon(3e-3));
  // A cut-off above the smallest singular value discards it, and the error stays bounded.
  const auto cut = hemisphere::least_squares(5, 1e-4);
  CHECK(cut.discarded == 1);
  CHECK(hemisphere::summarize(hemisphere::least_squares_error(5, cut)).worst < 1e-4);
}

TEST_CASE("the upper-hemisphere quadrature is exact", "[hemisphere][quadrature]") {
  const DirectionSet h = hemisphere::upper_quadrature(6);
  CHECK(h.weights.sum() == Approx(2 * M_PI).epsilon(1e-14));
  // int_H z dS = pi, int_H z^4 dS = 2 pi / 5
  CHECK(h.weights.dot(h.directions.col(2)) == Approx(M_PI).epsilon(1e-14));
  CHECK(h.weights.dot(h.directions.col(2).array().pow(4).matrix()) ==
        Approx(2 * M_PI / 5).epsilon(1e-14));
}
