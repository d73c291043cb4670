// Basis plug-ins beyond the conformance kit: Haar's fast projections agree
// with the dense product, the sparse non-linear approximation, and hsh.
#include <tbb/global_control.h>

#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <random>

#include "../common/scenes.hpp"
#include "../common/thread_communicator.hpp"
#include "prt/bake_file.hpp"
#include "prt/basis.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/hemisphere.hpp"
#include "prt/registry.hpp"
#include "prt/relight.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"

using namespace prt;

namespace {
PluginRegistry& registry() {
  static PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  return r;
}
std::shared_ptr<Basis> make(const std::string& name, std::map<std::string, ParamValue> values) {
  Params p;
  for (auto& [key, value] : values) p.set(key, value);
  return registry().create<Basis>(name, p);
}
Eigen::MatrixXd random_samples(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd m(rows, cols);
  for (auto& x : m.reshaped()) x = g(rng);
  return m;
}
}  // namespace

TEST_CASE("Haar: fast projections equal the dense product on any direction set", "[haar]") {
  const auto haar = make("haar", {{"resolution", std::int64_t(8)}});
  CHECK(haar->size() == 384);
  for (const DirectionSet& set : {DirectionSet::cubemap(8), DirectionSet::fibonacci(2000)}) {
    const Eigen::MatrixXd f = random_samples(3, set.size(), 1);
    const Eigen::MatrixXd fast = haar->project(f, set);
    const Eigen::MatrixXd dense = f * haar->projection_matrix(set);
    INFO(set.kind);
    CHECK((fast - dense).cwiseAbs().maxCoeff() < 1e-10 * dense.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("Haar: exact reconstruction on its lattice with all coefficients", "[haar]") {
  const auto haar = make("haar", {{"resolution", std::int64_t(4)}});
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const Eigen::MatrixXd f = random_samples(2, lattice.size(), 2);
  const Eigen::MatrixXd c = haar->project(f, lattice);
  const Eigen::MatrixXd back = c * haar->evaluate(lattice.directions).transpose();
  CHECK((back - f).cwiseAbs().maxCoeff() < 1e-12);
  // The integral of a product is the dot product of coefficients (Parseval
  // under the lattice's solid angles): what shading relies on.
  const double integral =
      (f.row(0).array() * f.row(1).array() * lattice.weights.transpose().array()).sum();
  CHECK(c.row(0).dot(c.row(1)) == Approx(integral).epsilon(1e-12));
  CHECK_THROWS_WITH(make("haar", {{"resolution", std::int64_t(6)}}), Catch::Contains("power of 2"));
}

TEST_CASE("the k largest coefficients, stored sparsely", "[haar][sparse]") {
  TransferSignal s;
  s.coefficients = MatrixXfRow(2, 5);
  s.coefficients << 0.1f, -3.f, 0.2f, 2.f, 0.f,  //
      1.f, 1.f, -4.f, 0.5f, 0.25f;
  const CompressedTransfer c = keep_largest(s, 2);
  REQUIRE(c.sparse());
  REQUIRE_NOTHROW(c.validate(2));
  CHECK(c.weight_index == std::vector<std::int32_t>{1, 3, 0, 2});  // ties broken by index
  MatrixXfRow expected = MatrixXfRow::Zero(2, 5);
  expected(0, 1) = -3.f, expected(0, 3) = 2.f, expected(1, 0) = 1.f, expected(1, 2) = -4.f;
  CHECK(c.decode() == expected);
  const Eigen::MatrixX3d light = random_samples(5, 3, 3);
  const Eigen::MatrixX3f lit = relight(c, light);
  CHECK((lit - (expected.cast<double>() * light).cast<float>()).cwiseAbs().maxCoeff() < 1e-5f);
  CHECK(c.stored_floats() == 2.0 * 2 * 2 + 5);
  // All terms kept: exact.
  CHECK(keep_largest(s, 5).decode() == s.coefficients);
  CHECK(keep_largest(s, 99).components == 5);
}

TEST_CASE("sparse compressed transfer survives the bake file", "[sparse][bake]") {
  BakeData d;
  d.mesh = make_box();
  d.basis = {"haar", "1", "k = 2\n"};
  d.compressor = {"none", "1", ""};
  d.transfer.coefficients = MatrixXfRow::Random(d.mesh.vertex_count(), 6);
  d.compressed = keep_largest(d.transfer, 2);
  const auto file = std::filesystem::temp_directory_path() / "prt_sparse.h5";
  write_bake(file, d);
  const BakeData r = read_bake(file);
  CHECK(r.compressed.weight_index == d.compressed.weight_index);
  CHECK(r.compressed.decode() == d.compressed.decode());
}

TEST_CASE("hsh: least squares recovers an order-N function from the hemisphere only", "[hsh]") {
  const auto hsh = make("hsh", {{"order", std::int64_t(5)}});
  const DirectionSet upper = hemisphere::upper_quadrature(6);
  const Eigen::RowVectorXd c = random_samples(1, 25, 4);
  const Eigen::RowVectorXd samples = c * sh::evaluate(5, upper.directions).transpose();
  CHECK((hsh->project(samples, upper) - c).norm() < 1e-8 * c.norm());
  // The zero-hemisphere projection does not (Sloan's 35% worst case).
  const auto zero = make("hsh", {{"order", std::int64_t(5)}, {"projection", std::string("zero")}});
  CHECK((zero->project(samples, upper) - c).norm() > 1e-3 * c.norm());
  // The reduced basis has 24 functions and refuses other projections.
  CHECK(make("hsh", {{"order", std::int64_t(5)}, {"reduced", true}})->size() == 24);
  CHECK_THROWS_WITH(make("hsh", {{"reduced", true}, {"projection", std::string("odd")}}),
                    Catch::Contains("least-squares"));
}

namespace {
// A sphere over a plane: 306 vertices, or 6,283, past the 4,096 rows from
// which the fit orthonormalises by Cholesky QR instead of Householder.
Mesh eigen_test_scene(bool large) {
  return large ? test::sphere_over_plane(4, 60) : test::sphere_over_plane();
}
}  // namespace

TEST_CASE("eigentransport: the randomized SVD finds the exact principal subspace", "[eigen]") {
  // 6 x 4 x 4 cube map: small enough for an exact SVD.
  const bool large = GENERATE(false, true);
  const Mesh scene = eigen_test_scene(large);
  CAPTURE(scene.vertex_count());
  REQUIRE((scene.vertex_count() > 4096) == large);
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const TransportResult r = test::trace_visibility_only(scene, lattice);
  auto eigen = make("eigen", {{"d", std::int64_t(6)}});
  eigen->fit({&scene, &lattice, &r.visibility});
  const Eigen::MatrixXd fitted = eigen->save().matrices.at("eigentransports");  // d x s
  REQUIRE(fitted.rows() == 6);

  Eigen::MatrixXd t;
  transport_rows(scene, lattice, r.visibility, 0, scene.vertex_count(), t);
  t = t * lattice.weights.cwiseSqrt().asDiagonal();
  t.rowwise() -= t.colwise().mean();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(t, Eigen::ComputeThinV);
  // Rows 1..5: the top 5 principal directions (same subspace: |E E_exact^T|^2 = 5).
  const Eigen::MatrixXd exact = svd.matrixV().leftCols(5).transpose();
  CHECK((fitted.bottomRows(5) * exact.transpose()).squaredNorm() == Approx(5.0).epsilon(1e-6));
  // Row 0: the mean's direction outside them; all rows orthonormal.
  CHECK((fitted * fitted.transpose() - Eigen::MatrixXd::Identity(6, 6)).cwiseAbs().maxCoeff() <
        1e-10);
  // The variance option picks the fewest components reaching the fraction.
  auto by_variance = make("eigen", {{"d", std::int64_t(40)}, {"variance", 0.9}});
  by_variance->fit({&scene, &lattice, &r.visibility});
  const Eigen::VectorXd s2 = svd.singularValues().array().square();
  int needed = 0;
  for (double captured = 0; captured < 0.9 * s2.sum(); ++needed) captured += s2[needed];
  CHECK(by_variance->size() == needed + 1);  // + the mean direction
  // Saved state restores an identical basis elsewhere.
  auto restored = make("eigen", {});
  restored->load(eigen->save());
  CHECK(restored->evaluate(lattice.directions) == eigen->evaluate(lattice.directions));
  CHECK_THROWS_WITH(make("eigen", {})->evaluate(lattice.directions), Catch::Contains("not fitted"));
}

TEST_CASE("eigentransport: ranks fitting from shards of the bits get the one-process basis",
          "[eigen][distributed]") {
  // 306 vertices (Q gathered for Householder QR) and ~20,000 (three segments,
  // Cholesky QR over segment sums; a row count whose columns are not aligned).
  const bool large = GENERATE(false, true);
  const Mesh scene = large ? test::sphere_over_plane(5, 100) : eigen_test_scene(false);
  CAPTURE(scene.vertex_count());
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const TransportResult r = test::trace_visibility_only(scene, lattice);
  const auto fitted = [](const Basis& basis) {
    return Eigen::MatrixXd(basis.save().matrices.at("eigentransports"));
  };
  auto one = make("eigen", {{"d", std::int64_t(6)}});
  REQUIRE(one->can_fit_distributed());
  one->fit({&scene, &lattice, &r.visibility});
  for (int ranks : {2, 3, 4}) {
    CAPTURE(ranks);
    std::vector<Eigen::MatrixXd> bases(static_cast<std::size_t>(ranks));
    test::run_on_ranks(ranks, [&](const Communicator& comm) {
      const Shard shard = shard_of(Eigen::Index(scene.vertex_count()), comm.rank(), ranks);
      const VisibilityBits bits =
          test::shard_bits(r.visibility, std::size_t(shard.first), std::size_t(shard.last));
      auto mine = make("eigen", {{"d", std::int64_t(6)}});
      mine->fit({&scene, &lattice, &bits, parts_over(comm, shard)});
      bases[std::size_t(comm.rank())] = fitted(*mine);
    });
    for (const auto& basis : bases) CHECK(basis == fitted(*one));  // bit for bit
  }
  // Bits that are not the shard's are refused.
  CHECK_THROWS_WITH(
      make("eigen", {})
          ->fit({&scene, &lattice, &r.visibility,
                 parts_over(solo(), shard_of(Eigen::Index(scene.vertex_count()), 0, 2))}),
      Catch::Contains("visibility of"));
}

TEST_CASE("eigentransport: identical transport rows (rank 0) give a finite orthonormal basis",
          "[eigen]") {
  // An open plane: every vertex sees the same upper hemisphere, so C = T W -
  // mean is zero. 5,041 vertices: Cholesky QR's Gram matrix is zero there and
  // the fit must take its Householder fallback, not divide by zero.
  const Mesh plane = make_plane(70, 5.f);
  REQUIRE(plane.vertex_count() > 4096);
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const TransportResult r = test::trace_visibility_only(plane, lattice);
  auto eigen = make("eigen", {{"d", std::int64_t(4)}});
  eigen->fit({&plane, &lattice, &r.visibility});
  const Eigen::MatrixXd fitted = eigen->save().matrices.at("eigentransports");
  REQUIRE(fitted.allFinite());
  CHECK((fitted * fitted.transpose() - Eigen::MatrixXd::Identity(fitted.rows(), fitted.rows()))
            .cwiseAbs()
            .maxCoeff() < 1e-10);
  // The mean transport is all there is: the basis reproduces it exactly.
  const Eigen::RowVectorXd mean = eigen->save().matrices.at("mean");
  CHECK((mean * fitted.transpose() * fitted - mean).norm() < 1e-10 * mean.norm());
  // No variance: the fraction captured is all of it, not rounding noise over zero.
  CHECK(eigen->save().matrices.at("captured_variance")(0, 0) == 1.0);
}

TEST_CASE("eigentransport: a seed gives the same basis on one core and on all", "[eigen]") {
  const Mesh scene = eigen_test_scene(GENERATE(false, true));
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const TransportResult r = test::trace_visibility_only(scene, lattice);
  auto fit = [&] {
    auto eigen = make("eigen", {{"d", std::int64_t(6)}});
    eigen->fit({&scene, &lattice, &r.visibility});
    return Eigen::MatrixXd(eigen->save().matrices.at("eigentransports"));
  };
  const Eigen::MatrixXd all_cores = fit();
  Eigen::MatrixXd one_core;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one_core = fit();
  }
  CHECK(one_core == all_cores);  // bit for bit: sums in a fixed order
}
