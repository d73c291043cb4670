#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "prt/quadrature.hpp"
#include "prt/sh.hpp"
#include "prt/sh_rotation.hpp"

using namespace prt;

namespace {
Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}
}  // namespace

TEST_CASE("SH match closed forms at l <= 2 (no Condon-Shortley phase)", "[sh]") {
  const double x = 0.36, y = -0.48, z = 0.8;  // unit
  double v[9];
  sh::evaluate(3, x, y, z, v);
  const double pi = M_PI;
  CHECK(v[0] == Approx(0.5 / std::sqrt(pi)).epsilon(1e-14));
  CHECK(v[1] == Approx(std::sqrt(3 / (4 * pi)) * y).epsilon(1e-14));
  CHECK(v[2] == Approx(std::sqrt(3 / (4 * pi)) * z).epsilon(1e-14));
  CHECK(v[3] == Approx(std::sqrt(3 / (4 * pi)) * x).epsilon(1e-14));
  CHECK(v[4] == Approx(0.5 * std::sqrt(15 / pi) * x * y).epsilon(1e-14));
  CHECK(v[5] == Approx(0.5 * std::sqrt(15 / pi) * y * z).epsilon(1e-14));
  CHECK(v[6] == Approx(0.25 * std::sqrt(5 / pi) * (3 * z * z - 1)).epsilon(1e-14));
  CHECK(v[7] == Approx(0.5 * std::sqrt(15 / pi) * x * z).epsilon(1e-14));
  CHECK(v[8] == Approx(0.25 * std::sqrt(15 / pi) * (x * x - y * y)).epsilon(1e-14));
  CHECK(sh::index(2, -2) == 4);
  CHECK(sh::index(3, 3) == 15);
}

TEST_CASE("SH are orthonormal to 1e-10 at every order 0..30 (exact quadrature)", "[sh]") {
  const DirectionSet set = gauss_product_sphere(31);  // exact to degree 61
  const Eigen::MatrixXd y = sh::evaluate(30, set.directions);
  const Eigen::MatrixXd gram = y.transpose() * set.weights.asDiagonal() * y;
  for (int order = 0; order <= 30; ++order) {
    const int n = order * order;
    const double error =
        (gram.topLeftCorner(n, n) - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff();
    INFO("order " << order);
    CHECK(error < 1e-10);
  }
}

TEST_CASE("SH stay finite and satisfy the addition theorem up to l = 150", "[sh][extremes]") {
  // sum_m y_lm(d)^2 = (2l + 1) / (4 pi) for every direction, poles included.
  const int order = 151;
  std::vector<double> v(order * order);
  const double dirs[][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0.6, 0, 0.8}, {1e-9, 0, 1}};
  for (const auto& d : dirs) {
    const Eigen::Vector3d n = Eigen::Vector3d(d[0], d[1], d[2]).normalized();
    sh::evaluate(order, n.x(), n.y(), n.z(), v.data());
    for (int l = 0; l < order; ++l) {
      double sum = 0;
      for (int m = -l; m <= l; ++m) {
        REQUIRE(std::isfinite(v[sh::index(l, m)]));
        sum += v[sh::index(l, m)] * v[sh::index(l, m)];
      }
      INFO("l = " << l);
      CHECK(sum == Approx((2 * l + 1) / (4 * M_PI)).epsilon(1e-10));
    }
  }
}

TEST_CASE("SH rotation: R(a) R(b) = R(ab), orthogonal, identity", "[sh][rotation]") {
  std::mt19937_64 rng(3);
  const Eigen::Matrix3d a = random_rotation(rng), b = random_rotation(rng);
  for (int order : {1, 2, 5, 10, 20}) {
    const Eigen::MatrixXd ra = sh::rotation(order, a), rb = sh::rotation(order, b);
    const Eigen::MatrixXd rab = sh::rotation(order, a * b);
    const int n = order * order;
    INFO("order " << order);
    CHECK((ra * rb - rab).cwiseAbs().maxCoeff() < 1e-11);
    CHECK((ra.transpose() * ra - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff() < 1e-11);
    CHECK((sh::rotation(order, Eigen::Matrix3d::Identity()) - Eigen::MatrixXd::Identity(n, n))
              .cwiseAbs()
              .maxCoeff() < 1e-14);
  }
}

TEST_CASE("rotating coefficients equals re-projecting the rotated function", "[sh][rotation]") {
  const int order = 10;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  Eigen::VectorXd c(order * order);
  for (auto& x : c) x = g(rng);
  const Eigen::Matrix3d r = random_rotation(rng);
  // g(d) = f(R^T d), sampled and projected with exact quadrature.
  const DirectionSet set = gauss_product_sphere(order + 1);
  Directions rotated_back = set.directions * r;  // rows: (R^T d)^T
  const Eigen::VectorXd samples = sh::evaluate(order, rotated_back) * c;
  const Eigen::VectorXd projected =
      sh::evaluate(order, set.directions).transpose() * set.weights.asDiagonal() * samples;
  const Eigen::VectorXd rotated = sh::rotation(order, r) * c;
  CHECK((rotated - projected).norm() / c.norm() < 1e-9);
}

TEST_CASE("clamped cosine zonal coefficients match closed forms", "[sh]") {
  const Eigen::VectorXd z = sh::clamped_cosine_zonal(8);
  CHECK(z[0] == Approx(std::sqrt(M_PI) / 2).epsilon(1e-14));
  CHECK(z[1] == Approx(std::sqrt(M_PI / 3)).epsilon(1e-14));
  CHECK(z[2] == Approx(std::sqrt(5 * M_PI) / 8).epsilon(1e-14));
  CHECK(std::abs(z[3]) < 1e-15);
  CHECK(z[4] == Approx(-std::sqrt(M_PI) / 16).epsilon(1e-13));  // -sqrt(9 pi)/48
  CHECK(std::abs(z[5]) < 1e-15);
  CHECK(sh::clamped_cosine_zonal(0).size() == 0);
}

TEST_CASE("SH windows damp high bands and the ringing of a bright spot", "[sh][window]") {
  for (const char* kind : {"none", "hanning", "lanczos"}) {
    const Eigen::VectorXd w = sh::window(12, kind);
    CHECK(w[0] == 1.0);
    for (int l = 1; l < 12; ++l) {
      CHECK(w[sh::index(l, 0)] <= w[sh::index(l - 1, 0)] + 1e-15);
      CHECK(w[sh::index(l, 0)] > 0.0);
      CHECK(w[sh::index(l, -l)] == w[sh::index(l, l)]);
    }
  }
  CHECK_THROWS_WITH(sh::window(5, "hamming"), Catch::Contains("hanning"));
  // A narrow bright lobe (the clamped cosine to a high power, projected):
  // windowing shrinks the negative area of its order-15 reconstruction.
  const DirectionSet q = gauss_product_sphere(40);
  const Eigen::Vector3d sun(0, 0.6, 0.8);
  Eigen::VectorXd samples(q.size());
  for (Eigen::Index k = 0; k < q.size(); ++k)
    samples[k] = 1.0 + 1e5 * std::pow(std::max(0.0, q.directions.row(k).dot(sun)), 400.0);
  const Eigen::MatrixXd y = sh::evaluate(15, q.directions);
  const Eigen::VectorXd c = y.transpose() * q.weights.asDiagonal() * samples;
  auto negative_area = [&](const Eigen::VectorXd& coefficients) {
    const Eigen::VectorXd f = y * coefficients;
    double area = 0;
    for (Eigen::Index k = 0; k < f.size(); ++k) area += f[k] < 0 ? q.weights[k] : 0.0;
    return area;
  };
  const double plain = negative_area(c);
  const Eigen::VectorXd windowed = sh::window(15, "hanning").cwiseProduct(c);
  CHECK(plain > 0.5);
  CHECK(negative_area(windowed) < 0.9 * plain);
  CHECK((y * windowed).minCoeff() > 0.2 * (y * c).minCoeff());  // 5x shallower troughs
}

TEST_CASE("block-diagonal rotation: apply and bands agree with the dense matrix",
          "[sh][rotation]") {
  std::mt19937_64 rng(5);
  for (int order : {1, 3, 10, 17}) {
    const Eigen::Matrix3d r = random_rotation(rng);
    const sh::Rotation rotation(order, r);
    const Eigen::MatrixXd dense = rotation.dense();
    const Eigen::MatrixXd in = Eigen::MatrixXd::Random(order * order, 3);
    Eigen::MatrixXd out(order * order, 3);
    rotation.apply(in, out);
    INFO("order " << order);
    CHECK((out - dense * in).cwiseAbs().maxCoeff() < 1e-13);
    for (int l = 0; l < order; ++l) {
      CHECK((rotation.band(l) - dense.block(l * l, l * l, 2 * l + 1, 2 * l + 1))
                .cwiseAbs()
                .maxCoeff() == 0.0);
      // off-diagonal blocks are exactly zero: nothing couples bands
      if (l > 0) CHECK(dense.block(l * l, 0, 2 * l + 1, l * l).cwiseAbs().maxCoeff() == 0.0);
    }
  }
  Eigen::MatrixXd wrong(5, 3), out(5, 3);
  CHECK_THROWS(sh::Rotation(3, Eigen::Matrix3d::Identity()).apply(wrong, out));
}

TEST_CASE("rotation at the degenerate Euler angles and at high degree", "[sh][rotation]") {
  // beta = 0 and beta = pi (rotations about z, and by pi about x): the l = 1
  // block is R itself in (y, z, x) order, the blocks stay orthogonal.
  const Eigen::Matrix3d about_x = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).matrix();
  const Eigen::Matrix3d tiny =
      Eigen::AngleAxisd(1e-12, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  for (const Eigen::Matrix3d& r : {about_x, tiny}) {
    const sh::Rotation rotation(12, r);
    const int perm[3] = {1, 2, 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        CHECK(rotation.band(1)(i, j) == Approx(r(perm[i], perm[j])).margin(1e-15));
    const Eigen::MatrixXd d = rotation.dense();
    CHECK((d * d.transpose() - Eigen::MatrixXd::Identity(144, 144)).cwiseAbs().maxCoeff() < 1e-13);
  }
  // One band at l = 300, alone: orthogonal to 1e-10 (Ivanic-Ruedenberg lost
  // that near l = 70).
  std::mt19937_64 rng(9);
  const int l = 300, size = 2 * l + 1;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> band(size, size);
  sh::rotation_band(l, random_rotation(rng), band.data());
  REQUIRE(band.allFinite());
  CHECK((band * band.transpose() - Eigen::MatrixXd::Identity(size, size)).cwiseAbs().maxCoeff() <
        1e-10);
}
