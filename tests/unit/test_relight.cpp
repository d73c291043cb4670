#include <catch2/catch.hpp>
#include <memory>

#include "prt/compressor.hpp"
#include "prt/pipeline.hpp"
#include "prt/registry.hpp"

using namespace prt;

TEST_CASE("the exact compressor decodes to the signal and relights as t . l", "[relight]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Params params;
  auto none = registry.create<Compressor>("none", params);
  TransferSignal s;
  s.coefficients = MatrixXfRow::Random(50, 16);
  const CompressedTransfer c = none->encode(s, nullptr);
  CHECK(c.decode() == s.coefficients);
  CHECK(c.clusters() == 50);  // a cluster per vertex, its mean the vertex's transfer
  CHECK(c.components == 0);
  CHECK(c.stored_floats() == 50.0 * 16);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(16, 3);
  const Eigen::MatrixX3f expected = (s.coefficients.cast<double>() * light).cast<float>();
  CHECK((relight(c, light) - expected).cwiseAbs().maxCoeff() < 1e-5f);
  CHECK_THROWS(relight(c, Eigen::MatrixX3d::Zero(9, 3)));
}

TEST_CASE("relighting uses per-cluster constants and per-vertex weights", "[relight]") {
  CompressedTransfer c;
  c.dimension = 2;
  c.components = 1;
  c.cluster_of_vertex = {0, 1, 1};
  c.weights = MatrixXfRow(3, 1);
  c.weights << 2, 3, -1;
  c.means = MatrixXfRow(2, 2);
  c.means << 1, 0, 0, 1;
  c.representatives = {MatrixXfRow::Constant(1, 2, 1), MatrixXfRow::Constant(1, 2, 2)};
  Eigen::MatrixX3d light(2, 3);
  light << 1, 1, 1, 10, 10, 10;
  const Eigen::MatrixX3f e = relight(c, light);
  CHECK(e(0, 0) == Approx(1 + 2 * 11));
  CHECK(e(1, 0) == Approx(10 + 3 * 22));
  CHECK(e(2, 0) == Approx(10 - 22));
}

TEST_CASE("vertex error statistics", "[relight]") {
  Eigen::MatrixX3f reference = Eigen::MatrixX3f::Ones(100, 3);
  Eigen::MatrixX3f approx = reference;
  approx.row(7).setConstant(2);
  const ErrorStats e = vertex_error(approx, reference);
  CHECK(e.rms == Approx(std::sqrt(1.0 / 100)));
  CHECK(e.max == Approx(1.0));
  CHECK(e.relative_rms == Approx(0.1));
  CHECK(vertex_error(reference, reference).rms == 0.0);
}
