// Compression in the rendered metric (issue 39): whitened rows carry the
// function-space norm, the map back inverts the whitening, and an encode in
// the metric is never worse in that norm than one in coefficient space.
#include <catch2/catch.hpp>
#include <random>

#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/registry.hpp"
#include "prt/rendered_metric.hpp"

using namespace prt;

namespace {
PluginRegistry& registry() {
  static PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  return r;
}
std::shared_ptr<Basis> make_basis(const std::string& name,
                                  std::map<std::string, ParamValue> values) {
  Params p;
  for (auto& [key, value] : values) p.set(key, value);
  return registry().create<Basis>(name, p);
}
// Glossy rows with a structure PCA can find: a few smooth patterns plus noise.
TransferSignal glossy_rows(Eigen::Index vertices, int exit_rows, int light, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  const int n = exit_rows * light;
  Eigen::MatrixXd patterns(6, n), mix(vertices, 6);
  for (auto& x : patterns.reshaped()) x = g(rng);
  for (auto& x : mix.reshaped()) x = g(rng);
  TransferSignal s;
  s.kind = "glossy";
  s.exit_rows = exit_rows;
  s.coefficients = (mix * patterns).cast<float>();
  for (auto& x : s.coefficients.reshaped()) x += 0.05f * float(g(rng));
  return s;
}
// tr(D^T G_e D G_l) summed over rows: the function-space error, computed
// straight from the Gram matrices.
double function_space_error(const TransferSignal& exact, const MatrixXfRow& approximation,
                            const Eigen::MatrixXd& gram_exit, const Eigen::MatrixXd& gram_light) {
  double sum = 0;
  const int r = exact.exit_rows;
  const Eigen::Index l = exact.dimension() / r;
  for (Eigen::Index p = 0; p < exact.vertices(); ++p) {
    Eigen::MatrixXd d(r, l);
    for (int i = 0; i < r; ++i)
      d.row(i) =
          (exact.coefficients.row(p).segment(i * l, l) - approximation.row(p).segment(i * l, l))
              .cast<double>();
    sum += (d.transpose() * gram_exit * d * gram_light).trace();
  }
  return sum;
}
}  // namespace

TEST_CASE("rendered metric: the identity for orthonormal bases, not for hsh or sg", "[metric]") {
  const auto sh = make_basis("sh", {{"order", std::int64_t(3)}});
  const auto hsh = make_basis("hsh", {{"order", std::int64_t(3)}});
  const auto sg = make_basis("sg", {{"lobes", std::int64_t(9)}});
  CHECK(RenderedMetric(*sh, nullptr).identity());
  CHECK_FALSE(RenderedMetric(*sh, hsh.get()).identity());
  CHECK_FALSE(RenderedMetric(*sg, nullptr).identity());
  CHECK(RenderedMetric().identity());
}

TEST_CASE("rendered metric: whitened rows carry the function-space norm and map back", "[metric]") {
  const auto light = make_basis("sg", {{"lobes", std::int64_t(9)}});
  const auto exit = make_basis("hsh", {{"order", std::int64_t(3)}});
  const RenderedMetric metric(*light, exit.get());
  const TransferSignal rows = glossy_rows(50, exit->size(), light->size(), 1);
  const TransferSignal whitened = metric.whiten(rows);
  const Eigen::MatrixXd gram_exit = gram_matrix(*exit), gram_light = gram_matrix(*light);
  const MatrixXfRow zero = MatrixXfRow::Zero(rows.vertices(), rows.dimension());
  const double expected = function_space_error(rows, zero, gram_exit, gram_light);
  const double got = whitened.coefficients.cast<double>().squaredNorm();
  CHECK(got == Approx(expected).epsilon(1e-5));
  MatrixXfRow back = whitened.coefficients;
  metric.unwhiten_rows(back, rows.exit_rows);
  CHECK((back - rows.coefficients).norm() <= 1e-4 * rows.coefficients.norm());
}

TEST_CASE("rendered metric: PCA in the metric beats PCA in coefficients, in the metric",
          "[metric]") {
  // Eckart-Young in the whitened coordinates: the rank-k PCA there is the
  // best rank-k approximation in the function-space norm, so the encode in
  // the metric can only be better; a wrong factor (transposed, inverted)
  // would lose this.
  const auto light = make_basis("sh", {{"order", std::int64_t(3)}});
  const auto exit = make_basis("hsh", {{"order", std::int64_t(4)}});
  const RenderedMetric metric(*light, exit.get());
  const TransferSignal rows = glossy_rows(400, exit->size(), light->size(), 2);
  Params params;
  params.set("components", std::int64_t(3));
  const auto pca = registry().create<Compressor>("pca", params);
  const Distribution whole = Distribution::whole_signal(rows.vertices());
  const CompressedTransfer plain = pca->encode(rows, nullptr);
  const CompressedTransfer in_metric = encode_in_metric(*pca, rows, nullptr, whole, metric);
  const Eigen::MatrixXd gram_exit = gram_matrix(*exit), identity = Eigen::MatrixXd::Identity(9, 9);
  const double plain_error = function_space_error(rows, plain.decode(), gram_exit, identity);
  const double metric_error = function_space_error(rows, in_metric.decode(), gram_exit, identity);
  INFO("function-space SE: coefficient-space PCA " << plain_error << ", PCA in the metric "
                                                   << metric_error);
  CHECK(metric_error < 0.98 * plain_error);
  // The report measures the same function-space error.
  const CompressionReport report = measure(rows, in_metric, nullptr, 0, whole, &metric);
  CHECK(report.rendered_metric);
  CHECK(report.squared_error == Approx(metric_error).epsilon(1e-4));
  // The identity metric leaves an encode as it was, bit for bit.
  const CompressedTransfer same =
      encode_in_metric(*pca, rows, nullptr, whole, RenderedMetric(*light, nullptr));
  CHECK(same.means == plain.means);
  CHECK(same.weights == plain.weights);
}
