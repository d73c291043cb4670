// Conformance checks run over every compressor plug-in (one ctest entry
// each). Compressors that expose the conventional parameters "clusters"
// and/or "components" get the budget checks through them.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>

#include "conformance.hpp"
#include "prt/compressor.hpp"
#include "prt/registry.hpp"

using namespace prt;

namespace {

struct Fixture {
  PluginRegistry registry{PluginRegistry::default_directories()};
  const PluginDescriptor& descriptor =
      registry.find(PluginKind::compressor, conformance::plugin_name);
  bool has(const char* key) const { return descriptor.schema().find(key) != nullptr; }

  std::shared_ptr<Compressor> make(std::map<std::string, std::int64_t> values = {}) {
    Params params;
    for (const auto& [key, value] : values)
      if (has(key.c_str())) params.set(key, value);
    return registry.create<Compressor>(conformance::plugin_name, params);
  }
};

// 12 blobs of rank 2 in 16 dimensions, plus noise.
TransferSignal test_signal(int points = 240, std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g;
  TransferSignal s;
  s.coefficients.resize(points, 16);
  MatrixXfRow centres(12, 16), axes(24, 16);
  for (auto& v : centres.reshaped()) v = 2.f * g(rng);
  for (auto& v : axes.reshaped()) v = g(rng);
  for (int p = 0; p < points; ++p) {
    const int k = p % 12;
    s.coefficients.row(p) =
        centres.row(k) + g(rng) * axes.row(2 * k) + 0.5f * g(rng) * axes.row(2 * k + 1);
    for (int d = 0; d < 16; ++d) s.coefficients(p, d) += 0.01f * g(rng);
  }
  return s;
}

double se(const TransferSignal& s, const CompressedTransfer& c) {
  return squared_error(s.coefficients, c.decode());
}

}  // namespace

TEST_CASE_METHOD(Fixture, "the compressed form is consistent and finite", "[conformance]") {
  const TransferSignal s = test_signal();
  const CompressedTransfer c = make()->encode(s, nullptr);
  REQUIRE_NOTHROW(c.validate(s.vertices()));
  CHECK(c.dimension == s.dimension());
  CHECK(c.decode().allFinite());
  const CompressionReport r = measure(s, c, nullptr, 0);
  CHECK(r.squared_error == Approx(se(s, c)));
  CHECK(r.stored_floats == c.stored_floats());
}

TEST_CASE_METHOD(Fixture, "exact at full rank", "[conformance]") {
  const TransferSignal s = test_signal();
  const double energy = s.coefficients.cast<double>().squaredNorm();
  // Full rank: n' = n, or one cluster per point, or no parameters at all.
  std::map<std::string, std::int64_t> full;
  if (has("components"))
    full = {{"components", s.dimension()}, {"clusters", 4}};
  else if (has("clusters"))
    full = {{"clusters", s.vertices()}};
  CHECK(se(s, make(full)->encode(s, nullptr)) <= 1e-10 * energy);
}

TEST_CASE_METHOD(Fixture, "squared error does not grow with the budget", "[conformance]") {
  const TransferSignal s = test_signal();
  if (has("components")) {
    double previous = INFINITY;
    for (std::int64_t n : {0, 1, 2, 4, 8, 16}) {
      const double e = se(s, make({{"components", n}, {"clusters", 6}})->encode(s, nullptr));
      INFO("components " << n);
      CHECK(e <= previous * (1 + 1e-9) + 1e-12);
      previous = e;
    }
  }
  if (has("clusters")) {
    double previous = INFINITY;
    for (std::int64_t k : {1, 3, 12, 48, 240}) {
      const double e = se(s, make({{"clusters", k}, {"components", 1}})->encode(s, nullptr));
      INFO("clusters " << k);
      CHECK(e <= previous * 1.01 + 1e-12);  // k-means local optima may reverse by a hair
      previous = e;
    }
  }
}

TEST_CASE_METHOD(Fixture, "deterministic for a seed", "[conformance]") {
  const TransferSignal s = test_signal();
  const CompressedTransfer a = make()->encode(s, nullptr), b = make()->encode(s, nullptr);
  CHECK(a.cluster_of_vertex == b.cluster_of_vertex);
  CHECK(a.weights == b.weights);
  CHECK(a.means == b.means);
}

TEST_CASE_METHOD(Fixture, "degenerate inputs give a valid form, never NaN",
                 "[conformance][extremes]") {
  TransferSignal same;
  same.coefficients = MatrixXfRow::Constant(20, 16, 0.25f);
  TransferSignal one;
  one.coefficients = MatrixXfRow::Constant(1, 16, -1.f);
  TransferSignal few = test_signal(5);  // fewer points than clusters and than n'
  for (const TransferSignal* s : {&same, &one, &few}) {
    const CompressedTransfer c = make({{"clusters", 8}, {"components", 24}})->encode(*s, nullptr);
    REQUIRE_NOTHROW(c.validate(s->vertices()));
    CHECK(c.decode().allFinite());
    CHECK(se(*s, c) <= 1e-10 * (1 + s->coefficients.cast<double>().squaredNorm()));
  }
}

TEST_CASE_METHOD(Fixture, "NaN or Inf input is refused naming the vertex",
                 "[conformance][extremes]") {
  TransferSignal s = test_signal();
  if (make()->exact()) {  // an exact compressor stores the signal as it is, NaN included
    s.coefficients(17, 3) = NAN;
    MatrixXfRow decoded = make()->encode(s, nullptr).decode();
    CHECK(std::isnan(decoded(17, 3)));
    decoded.row(17).setZero();  // the NaN spreads through vertex 17's reconstruction
    s.coefficients.row(17).setZero();
    CHECK(decoded == s.coefficients);
    return;
  }
  s.coefficients(17, 3) = NAN;
  CHECK_THROWS_WITH(make()->encode(s, nullptr), Catch::Contains("vertex 17"));
  s.coefficients(17, 3) = INFINITY;
  CHECK_THROWS_WITH(make()->encode(s, nullptr), Catch::Contains("vertex 17"));
}
