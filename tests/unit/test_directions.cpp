#include <catch2/catch.hpp>
#include <cmath>

#include "prt/direction_set.hpp"
#include "prt/quadrature.hpp"

using namespace prt;

namespace {
void check_unit_and_total(const DirectionSet& set) {
  for (Eigen::Index k = 0; k < set.size(); ++k)
    REQUIRE(set.directions.row(k).norm() == Approx(1.0).epsilon(1e-12));
  CHECK(set.weights.sum() == Approx(4 * M_PI).epsilon(1e-12));
  CHECK(set.weights.minCoeff() > 0);
}
}  // namespace

TEST_CASE("direction sets are unit vectors whose weights sum to 4 pi", "[directions]") {
  check_unit_and_total(DirectionSet::fibonacci(1));
  check_unit_and_total(DirectionSet::fibonacci(1000));
  check_unit_and_total(DirectionSet::stratified(1, 5));
  check_unit_and_total(DirectionSet::stratified(777, 5));
  check_unit_and_total(DirectionSet::cubemap(1));
  check_unit_and_total(DirectionSet::cubemap(16));
  check_unit_and_total(DirectionSet::equirect(64, 32, 0, 32));
  check_unit_and_total(gauss_product_sphere(12));
  CHECK(DirectionSet::cubemap(16).size() == 6 * 16 * 16);
  CHECK(DirectionSet::make("cubemap", 1536, 0).size() == 1536);
  CHECK_THROWS_WITH(DirectionSet::make("spiral", 10, 0), Catch::Contains("fibonacci"));
  CHECK_THROWS(DirectionSet::fibonacci(0));
}

TEST_CASE("stratified directions are deterministic per seed", "[directions]") {
  const auto a = DirectionSet::stratified(500, 42), b = DirectionSet::stratified(500, 42);
  const auto c = DirectionSet::stratified(500, 43);
  CHECK(a.directions == b.directions);
  CHECK(a.directions != c.directions);
}

TEST_CASE("direction sets integrate x^2 over the sphere to 4 pi / 3", "[directions]") {
  for (const auto& set : {DirectionSet::fibonacci(4096), DirectionSet::stratified(4096, 1),
                          DirectionSet::cubemap(32), DirectionSet::equirect(256, 128, 0, 128)}) {
    const double integral = set.weights.dot(set.directions.col(0).array().square().matrix());
    INFO(set.kind);
    CHECK(integral == Approx(4 * M_PI / 3).epsilon(2e-3));
  }
}

TEST_CASE("Gauss-Legendre is exact for polynomials of degree 2n - 1", "[quadrature]") {
  const auto rule = gauss_legendre(5);
  double integral = 0;
  for (int i = 0; i < 5; ++i) integral += rule.weights[i] * std::pow(rule.nodes[i], 8);
  CHECK(integral == Approx(2.0 / 9.0).epsilon(1e-14));
  CHECK(gauss_legendre(1).weights[0] == Approx(2.0));
}

TEST_CASE("equirect uv and direction are inverse", "[directions]") {
  for (double u : {0.1, 0.5, 0.9})
    for (double v : {0.05, 0.5, 0.95}) {
      const Eigen::Vector2d back = equirect_uv(equirect_direction(u, v));
      CHECK(back.x() == Approx(u).epsilon(1e-12));
      CHECK(back.y() == Approx(v).epsilon(1e-12));
    }
  CHECK(equirect_direction(0.3, 0.0).y() == Approx(1.0));  // top row is +y
}

TEST_CASE("every cube-map texel centre maps back to its own texel", "[directions]") {
  for (int r : {1, 4, 32}) {
    const DirectionSet set = DirectionSet::cubemap(r);
    for (Eigen::Index k = 0; k < set.size(); ++k)
      REQUIRE(cubemap_texel(set.directions.row(k).transpose(), r) == k);
  }
}
