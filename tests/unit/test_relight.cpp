#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>

#include "prt/compressor.hpp"
#include "prt/pipeline.hpp"
#include "prt/registry.hpp"
#include "prt/relight.hpp"
#include "prt/view_transfer.hpp"

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

namespace {

// A compressed transfer with clusters of every kernel size (n'_k = 0..17,
// fixed-size and generic kernels), an empty cluster and clusters larger than
// one block of vertices, in scrambled vertex order.
CompressedTransfer mixed_clusters(Eigen::Index dimension, int vertices) {
  CompressedTransfer c;
  c.dimension = dimension;
  const int clusters = 19;
  c.components = 17;
  c.means = MatrixXfRow::Random(clusters, dimension);
  for (int k = 0; k < clusters; ++k)
    c.representatives.push_back(MatrixXfRow::Random(k == 18 ? 0 : k, dimension));
  c.weights = MatrixXfRow::Zero(vertices, c.components);
  for (int p = 0; p < vertices; ++p) {
    const int k = (p * 7919) % clusters == 5 ? 6 : (p * 7919) % clusters;  // cluster 5 empty
    c.cluster_of_vertex.push_back(k);
    const int n_k = c.components_of(k);
    c.weights.row(p).head(n_k) = Eigen::RowVectorXf::Random(n_k);
  }
  return c;
}

// A cluster per vertex, each its mean alone (as the exact form): one
// stored row per cluster, of 21 coefficients (one packet and a tail of the
// row-by-row dots).
CompressedTransfer exact_like(int vertices) {
  CompressedTransfer c;
  c.dimension = 21;
  c.means = MatrixXfRow::Random(vertices, c.dimension);
  c.representatives.assign(std::size_t(vertices), MatrixXfRow(0, c.dimension));
  c.weights = MatrixXfRow::Zero(vertices, 0);
  for (int p = 0; p < vertices; ++p) c.cluster_of_vertex.push_back(p);
  return c;
}
}  // namespace

TEST_CASE("the relight kernel matches the decoded transfer for every cluster shape", "[relight]") {
  const CompressedTransfer c = mixed_clusters(12, 1500);
  c.validate(1500);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(12, 3);
  const Eigen::MatrixX3f expected = (c.decode().cast<double>() * light).cast<float>();
  const RelightKernel kernel(c, 1);
  const Eigen::MatrixX3f once = kernel.radiance(light);
  CHECK((once - expected).cwiseAbs().maxCoeff() < 1e-4f);
  CHECK(kernel.radiance(light) == once);  // the layout is reused, not consumed
  // exit coefficients of a diffuse transfer are its radiance, RGB interleaved
  const MatrixXfRow e = kernel.exit_coefficients(light);
  CHECK((e - MatrixXfRow(once)).cwiseAbs().maxCoeff() < 1e-5f);
  CHECK(kernel.streamed_bytes(false) > 0);
}

TEST_CASE("the glossy relight kernel dots each exit vector with the exit values", "[relight]") {
  const int rows = 5, n_i = 4, vertices = 700;
  const CompressedTransfer c = mixed_clusters(rows * n_i, vertices);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(n_i, 3);
  const MatrixXfRow values = MatrixXfRow::Random(vertices, rows);
  const MatrixXfRow decoded = c.decode();
  Eigen::MatrixX3f expected(vertices, 3);
  for (int p = 0; p < vertices; ++p) {
    const Eigen::MatrixXd m =
        Eigen::Map<const MatrixXfRow>(decoded.row(p).data(), rows, n_i).cast<double>();
    expected.row(p) = (values.row(p).cast<double>() * m * light).cast<float>();
  }
  const RelightKernel kernel(c, rows);
  CHECK((kernel.radiance(light, &values) - expected).cwiseAbs().maxCoeff() < 1e-4f);
  CHECK((relight(c, light, &values) - expected).cwiseAbs().maxCoeff() < 1e-4f);
  CHECK_THROWS_WITH(kernel.radiance(light), Catch::Contains("exit basis"));
  const MatrixXfRow wrong = MatrixXfRow::Zero(vertices, rows + 1);
  CHECK_THROWS_WITH(kernel.radiance(light, &wrong), Catch::Contains("exit values"));
  CHECK_THROWS(RelightKernel(c, 7));  // 20 coefficients do not form 7 rows
}

TEST_CASE("the relight kernel's result does not depend on how many parts it is split in",
          "[relight]") {
  // 13,000 vertices: one part in a one-thread arena, one per thread (at
  // least 4,096 vertices each: up to 3) otherwise; 100 coefficients: six
  // packets and a tail.
  const int vertices = 13000;
  const CompressedTransfer c = mixed_clusters(100, vertices);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(100, 3);
  const Eigen::MatrixX3f expected = (c.decode().cast<double>() * light).cast<float>();
  const auto radiance = [&](int threads, const MatrixXfRow* values, int rows) {
    Eigen::MatrixX3f out;
    tbb::task_arena(threads).execute([&] {
      const RelightKernel kernel(c, rows);
      kernel.radiance(rows == 1 ? light : Eigen::MatrixX3d(light.topRows(100 / rows)), values, out);
    });
    return out;
  };
  const Eigen::MatrixX3f one = radiance(1, nullptr, 1);
  CHECK((one - expected).cwiseAbs().maxCoeff() < 1e-4f);
  CHECK(radiance(tbb::this_task_arena::max_concurrency(), nullptr, 1) == one);
  CHECK(radiance(3, nullptr, 1) == one);
  const MatrixXfRow values = MatrixXfRow::Random(vertices, 4);  // glossy: 4 rows of 25
  const Eigen::MatrixX3f glossy = radiance(1, &values, 4);
  CHECK(glossy.allFinite());
  CHECK(radiance(tbb::this_task_arena::max_concurrency(), &values, 4) == glossy);
  CHECK(radiance(3, &values, 4) == glossy);
}

TEST_CASE("the relight kernel's per-part constants agree with its shared ones", "[relight]") {
  // A cluster per vertex, as the exact form: up to 4 MB of constants the
  // parts share, computed 16 stored rows at a time from panels; past that
  // (360,000 clusters) each part computes its own runs' constants row by row.
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(21, 3);
  for (const int vertices : {20001, 360000}) {  // 20,001: a last panel of one row
    const CompressedTransfer c = exact_like(vertices);
    const Eigen::MatrixX3f expected = (c.means.cast<double>() * light).cast<float>();
    const RelightKernel kernel(c, 1);
    INFO(vertices << " clusters");
    CHECK(kernel.shares_constants() == (vertices < 360000));
    CHECK((kernel.radiance(light) - expected).cwiseAbs().maxCoeff() < 1e-5f);
  }
}

TEST_CASE("cluster constants are each row's own, whatever panels share a call", "[relight]") {
  // One core walks all panels in one call: groups of six, three, then
  // single panels (1 to 14 panels reach every mix); all cores split them.
  // Each row must be its own dot with the light, on any split, with every
  // lane and channel in its place.
  const Eigen::MatrixX3f light = Eigen::MatrixX3f::Random(21, 3);
  for (int panels = 1; panels <= 14; ++panels) {
    const int clusters = 16 * panels - 3;  // one stored row each: a short last panel
    const CompressedTransfer c = exact_like(clusters);
    const ClusterConstants constants(c, 1);
    std::vector<float> one_core, all_cores;
    tbb::task_arena(1).execute([&] { constants.compute(light, one_core); });
    constants.compute(light, all_cores);
    INFO(panels << " panels");
    CHECK(one_core == all_cores);
    const MatrixXfRow expected = (c.means.cast<double>() * light.cast<double>()).cast<float>();
    float worst = 0;
    for (int k = 0; k < clusters; ++k)
      for (int channel = 0; channel < 3; ++channel)
        worst = std::max(worst, std::abs(one_core[std::size_t(constants.begin(k) + channel)] -
                                         expected(k, channel)));
    CHECK(worst < 1e-5f);
  }
}

TEST_CASE("cluster constants from panels match the per-cluster constants", "[relight]") {
  const int rows = 3, n_i = 7;  // 21 coefficients: 3 exit rows of 7
  const CompressedTransfer c = mixed_clusters(rows * n_i, 300);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(n_i, 3);
  const ClusterConstants constants(c, rows);
  std::vector<float> values;
  constants.compute(light.cast<float>(), values);
  const std::vector<MatrixXfRow> expected = cluster_constants(c, light, rows);
  for (Eigen::Index k = 0; k < c.clusters(); ++k) {
    INFO("cluster " << k);
    const Eigen::Map<const MatrixXfRow> got(values.data() + constants.begin(k),
                                            c.components_of(k) + 1, 3 * rows);
    CHECK((got - expected[std::size_t(k)]).cwiseAbs().maxCoeff() < 1e-5f);
  }
  CHECK(ClusterConstants::floats_for(c, rows) == constants.begin(c.clusters() - 1) + 3 * rows);
  CHECK_THROWS_WITH(constants.compute(Eigen::MatrixX3f::Ones(n_i + 1, 3), values),
                    Catch::Contains("light has 8 coefficients"));
  CHECK_THROWS_WITH(ClusterConstants(c, 4), Catch::Contains("no clusters of 4 exit rows"));
  CHECK_THROWS_WITH(ClusterConstants::bytes_for(c, 0), Catch::Contains("no clusters of 0"));
  CompressedTransfer short_representative = c;
  short_representative.representatives[3] = MatrixXfRow::Zero(3, rows * n_i - 1);
  CHECK_THROWS_WITH(ClusterConstants(short_representative, rows),
                    Catch::Contains("inconsistent sizes"));
  CompressedTransfer missing_cluster = c;
  missing_cluster.representatives.pop_back();
  CHECK_THROWS_WITH(ClusterConstants::floats_for(missing_cluster, rows),
                    Catch::Contains("inconsistent sizes"));
  // No coefficients: every constant is an empty sum.
  CompressedTransfer empty = mixed_clusters(0, 40);
  const ClusterConstants none(empty, 1);
  none.compute(Eigen::MatrixX3f(0, 3), values);
  CHECK(std::all_of(values.begin(), values.end(), [](float v) { return v == 0.f; }));
  CHECK(RelightKernel(empty, 1).radiance(Eigen::MatrixX3d(0, 3)).isZero());
}

namespace {

// Glossy radiance y(v_p)^T M_p l in double from the decoded transfer.
Eigen::MatrixX3f glossy_reference(const CompressedTransfer& c, const MatrixXfRow& values,
                                  const Eigen::MatrixX3d& light) {
  const MatrixXfRow decoded = c.decode();
  const Eigen::Index rows = values.cols(), n_l = light.rows();
  Eigen::MatrixX3f expected(c.vertices(), 3);
  for (Eigen::Index p = 0; p < c.vertices(); ++p) {
    const Eigen::MatrixXd m =
        Eigen::Map<const MatrixXfRow>(decoded.row(p).data(), rows, n_l).cast<double>();
    expected.row(p) = (values.row(p).cast<double>() * m * light).cast<float>();
  }
  return expected;
}

}  // namespace

TEST_CASE("a view folds glossy transfer toward the camera: t_p . l equals the kernel's sums",
          "[relight][view]") {
  const int rows = 6, n_l = 9;
  // Clusters of every size, some over one block (512) of vertices.
  const int vertices = 19 * 700;
  const CompressedTransfer c = mixed_clusters(rows * n_l, vertices);
  const MatrixXfRow values = MatrixXfRow::Random(vertices, rows);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(n_l, 3);
  const ViewTransfer view(c, values);
  CHECK(view.vertices() == vertices);
  CHECK(view.light_size() == n_l);
  const Eigen::MatrixX3f expected = glossy_reference(c, values, light);
  const Eigen::MatrixX3f once = view.radiance(light);
  CHECK((once - expected).cwiseAbs().maxCoeff() < 1e-4f);
  const RelightKernel kernel(c, rows);
  CHECK((once - kernel.radiance(light, &values)).cwiseAbs().maxCoeff() < 1e-4f);
  CHECK(view.radiance(light) == once);  // frame after frame, the same folded vectors
  // The light-space vectors themselves: M_p^T y_p.
  const MatrixXfRow t = view.light_space();
  const MatrixXfRow decoded = c.decode();
  for (int p : {0, 1, 4321, vertices - 1}) {
    const Eigen::RowVectorXf t_p =
        values.row(p) * Eigen::Map<const MatrixXfRow>(decoded.row(p).data(), rows, n_l);
    CHECK((t.row(p) - t_p).cwiseAbs().maxCoeff() < 1e-4f);
  }
  // Its frame streams n_L floats a vertex, fewer than the kernel's weights and exit values here.
  CHECK(view.streamed_bytes() >= double(vertices) * (n_l + 3) * sizeof(float));
  CHECK(view.streamed_bytes() < kernel.streamed_bytes(true));
}

TEST_CASE("a view's result does not depend on the number of threads", "[relight][view]") {
  const int rows = 4, n_l = 16, vertices = 9001;  // a last packet of one vertex
  const CompressedTransfer c = mixed_clusters(rows * n_l, vertices);
  const MatrixXfRow values = MatrixXfRow::Random(vertices, rows);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(n_l, 3);
  const Eigen::MatrixX3f many = ViewTransfer(c, values).radiance(light);
  Eigen::MatrixX3f one;
  tbb::task_arena(1).execute([&] { one = ViewTransfer(c, values).radiance(light); });
  CHECK(one == many);
}

TEST_CASE("a view of exact, sparse and empty transfers, and its refusals", "[relight][view]") {
  const int rows = 3, n_l = 7;
  // Exact form: a cluster per vertex, no components.
  const CompressedTransfer exact = exact_like(40);  // 21 coefficients = 3 x 7
  const MatrixXfRow values = MatrixXfRow::Random(40, rows);
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(n_l, 3);
  CHECK((ViewTransfer(exact, values).radiance(light) - glossy_reference(exact, values, light))
            .cwiseAbs()
            .maxCoeff() < 1e-5f);
  // Sparse form (the largest terms of each vertex, Haar's non-linear approximation).
  TransferSignal s;
  s.coefficients = MatrixXfRow::Random(40, rows * n_l);
  const CompressedTransfer sparse = keep_largest(s, 5);
  REQUIRE(sparse.sparse());
  CHECK((ViewTransfer(sparse, values).radiance(light) - glossy_reference(sparse, values, light))
            .cwiseAbs()
            .maxCoeff() < 1e-5f);
  // No vertices: an empty frame.
  CompressedTransfer none = exact_like(0);
  CHECK(ViewTransfer(none, MatrixXfRow(0, rows)).radiance(light).rows() == 0);
  // Refusals: exit values of another mesh or of a size that does not divide
  // the coefficients; a light of another size or not finite.
  CHECK_THROWS_WITH(ViewTransfer(exact, MatrixXfRow::Zero(39, rows)),
                    Catch::Contains("exit values are 39 x 3"));
  CHECK_THROWS_WITH(ViewTransfer(exact, MatrixXfRow::Zero(40, 4)),
                    Catch::Contains("does not fit 40 vertices of 21 coefficients"));
  const ViewTransfer view(exact, values);
  CHECK_THROWS_WITH(view.radiance(Eigen::MatrixX3d::Zero(8, 3)), Catch::Contains("finite 7 x 3"));
  Eigen::MatrixX3d nan = light;
  nan(2, 1) = std::nan("");
  CHECK_THROWS_WITH(view.radiance(nan), Catch::Contains("finite 7 x 3"));
}
