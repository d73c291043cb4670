// Conformance checks run over every basis plug-in (one ctest entry each):
// orthonormality if claimed, projection/reconstruction round trip, linearity,
// rotation consistency if it rotates, save/load round trip, extreme inputs.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <random>

#include "../common/scenes.hpp"
#include "conformance.hpp"
#include "prt/basis.hpp"
#include "prt/mesh.hpp"
#include "prt/quadrature.hpp"
#include "prt/registry.hpp"
#include "prt/transport.hpp"

using namespace prt;

namespace {

// Data-driven bases are fitted first, to a small scene of their own: a sphere
// over a plane, traced on a 6 x 8 x 8 cube map.
std::shared_ptr<Basis> fitted(std::shared_ptr<Basis> basis) {
  if (!basis->can_fit()) return basis;
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet lattice = DirectionSet::cubemap(8);
  const TransportResult r = test::trace_visibility_only(scene, lattice);
  basis->fit({&scene, &lattice, &r.visibility});
  return basis;
}

struct Fixture {
  PluginRegistry registry{PluginRegistry::default_directories()};
  Params params;
  std::shared_ptr<Basis> basis = fitted(registry.create<Basis>(conformance::plugin_name, params));
  // The basis's own exact rule, or one exact for spherical polynomials of degree < 128.
  DirectionSet set = basis->native_directions().value_or(gauss_product_sphere(64));
};

Eigen::MatrixXd random_coefficients(int functions, int size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd c(functions, size);
  for (auto& x : c.reshaped()) x = g(rng);
  return c;
}

}  // namespace

TEST_CASE_METHOD(Fixture, "basis values are finite everywhere, poles included", "[conformance]") {
  Directions extremes(6, 3);
  extremes << 0, 0, 1, 0, 0, -1, 1, 0, 0, 0, 1, 0, 1e-12, 0, 1, 0, -1e-12, -1;
  extremes.row(4).normalize(), extremes.row(5).normalize();
  const Eigen::MatrixXd v = basis->evaluate(extremes);
  CHECK(v.rows() == 6);
  CHECK(v.cols() == basis->size());
  CHECK(v.allFinite());
}

TEST_CASE_METHOD(Fixture, "an orthonormal basis has an identity Gram matrix", "[conformance]") {
  if (!basis->orthonormal()) return;
  const Eigen::MatrixXd y = basis->evaluate(set.directions);
  const Eigen::MatrixXd gram = y.transpose() * set.weights.asDiagonal() * y;
  const int n = basis->size();
  CHECK((gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE_METHOD(Fixture, "projection reconstructs functions in the span", "[conformance]") {
  const Eigen::MatrixXd c = random_coefficients(4, basis->size(), 1);
  const Eigen::MatrixXd samples = c * basis->evaluate(set.directions).transpose();
  const Eigen::MatrixXd projected = basis->project(samples, set);
  CHECK((projected - c).norm() / c.norm() < 1e-9);
}

TEST_CASE_METHOD(Fixture, "projection is linear and scales from 1e-6 to 1e6", "[conformance]") {
  const Eigen::MatrixXd f = random_coefficients(2, set.size(), 2);
  const Eigen::MatrixXd pf = basis->project(f, set);
  const Eigen::MatrixXd combined = basis->project(3.0 * f.row(0) - 0.5 * f.row(1), set);
  CHECK((combined - (3.0 * pf.row(0) - 0.5 * pf.row(1))).norm() < 1e-9 * pf.norm());
  for (double scale : {1e-6, 1e6}) {
    const Eigen::MatrixXd scaled = basis->project(scale * f, set);
    REQUIRE(scaled.allFinite());
    CHECK((scaled / scale - pf).norm() < 1e-12 * pf.norm());
  }
  CHECK(basis->project(Eigen::MatrixXd::Zero(1, set.size()), set).cwiseAbs().maxCoeff() == 0.0);
  // A constant function (every basis must cope, even if it is not in the span).
  const Eigen::MatrixXd constant =
      basis->project(Eigen::MatrixXd::Constant(1, set.size(), 2.5), set);
  CHECK(constant.allFinite());
  CHECK(constant.cwiseAbs().maxCoeff() > 0);
}

TEST_CASE_METHOD(Fixture, "rotation is consistent with re-projection and composes",
                 "[conformance]") {
  if (!basis->can_rotate()) return;
  const Eigen::Matrix3d a =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d b = Eigen::AngleAxisd(-1.9, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::MatrixXd ra = basis->rotation_matrix(a), rb = basis->rotation_matrix(b);
  CHECK((ra * rb - basis->rotation_matrix(a * b)).cwiseAbs().maxCoeff() < 1e-10);
  // Rotating coefficients equals projecting f(A^T d).
  const Eigen::VectorXd c = random_coefficients(1, basis->size(), 3).transpose();
  const Directions back = set.directions * a;
  const Eigen::RowVectorXd samples = (basis->evaluate(back) * c).transpose();
  const Eigen::VectorXd reprojected = basis->project(samples, set).transpose();
  CHECK((ra * c - reprojected).norm() / c.norm() < 1e-9);
}

TEST_CASE_METHOD(Fixture, "saved state restores an identical basis", "[conformance]") {
  const BasisState state = basis->save();
  Params fresh_params;
  auto fresh = registry.create<Basis>(conformance::plugin_name, fresh_params);
  fresh->load(state);
  CHECK(fresh->size() == basis->size());
  CHECK(fresh->evaluate(set.directions) == basis->evaluate(set.directions));
}

TEST_CASE_METHOD(Fixture, "every integer parameter works at its smallest and largest value",
                 "[conformance][extremes]") {
  const ParamSchema schema = registry.find(PluginKind::basis, conformance::plugin_name).schema();
  Directions extremes(4, 3);
  extremes << 0, 0, 1, 0, 0, -1, 1, 0, 0, 0.6, 0, 0.8;
  for (const auto& spec : schema.specs) {
    if (spec.type != ParamType::integer || std::string(spec.name) == "seed") continue;
    for (double value : {spec.min, spec.max}) {
      INFO(spec.name << " = " << value);
      Params p;
      p.set(spec.name, static_cast<std::int64_t>(value));
      std::shared_ptr<Basis> b;
      try {
        b = fitted(registry.create<Basis>(conformance::plugin_name, p));
      } catch (const Error& e) {
        // A value the schema allows may still be refused with a clear message
        // (e.g. a resolution that is not a power of 2) -- but never crash.
        CHECK(std::string(e.what()).find(spec.name) != std::string::npos);
        continue;
      }
      const Eigen::MatrixXd v = b->evaluate(extremes);
      CHECK(v.allFinite());
      CHECK(v.cols() == b->size());
      if (value == spec.min) {  // small enough for the round trip
        const DirectionSet native = b->native_directions().value_or(gauss_product_sphere(64));
        const Eigen::MatrixXd c = random_coefficients(2, b->size(), 5);
        const Eigen::MatrixXd back =
            b->project(c * b->evaluate(native.directions).transpose(), native);
        CHECK((back - c).norm() <= 1e-8 * c.norm());
      }
    }
  }
}
