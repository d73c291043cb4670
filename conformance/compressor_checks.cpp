// Conformance checks run over every compressor plug-in (one ctest entry
// each). Compressors that expose the conventional parameters "clusters"
// and/or "components" get the budget checks through them.
#include <cmath>
#include <map>
#include <random>

#include "kit.hpp"
#include "prt/compressor.hpp"
#include "prt/registry.hpp"

namespace prt::conformance {

namespace {

struct Fixture {
  explicit Fixture(Kit& kit)
      : registry(kit.registry),
        plugin(kit.plugin),
        schema(registry.find(PluginKind::compressor, plugin).schema()) {}
  PluginRegistry& registry;
  std::string plugin;
  ParamSchema schema;  // a copy: creating a Python plug-in may change the registry
  bool has(const char* key) const { return schema.find(key) != nullptr; }

  std::shared_ptr<Compressor> make(std::map<std::string, std::int64_t> values = {}) {
    Params params;
    for (const auto& [key, value] : values)
      if (has(key.c_str())) params.set(key, value);
    return registry.create<Compressor>(plugin, params);
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

static void compressor_check_0(Kit& kit) {
  Fixture fixture(kit);
  const TransferSignal s = test_signal();
  const CompressedTransfer c = fixture.make()->encode(s, nullptr);
  KIT_REQUIRE_NOTHROW(kit, c.validate(s.vertices()));
  KIT_CHECK_EQUAL(kit, c.dimension, s.dimension());
  KIT_CHECK(kit, c.decode().allFinite());
  const CompressionReport r = measure(s, c, nullptr, 0);
  KIT_CHECK_AT_MOST(kit, std::abs(r.squared_error - se(s, c)),
                    1.2e-5 * se(s, c));  // Catch's Approx
  KIT_CHECK_EQUAL(kit, r.stored_floats, c.stored_floats());
}

static void compressor_check_1(Kit& kit) {
  Fixture fixture(kit);
  const TransferSignal s = test_signal();
  const double energy = s.coefficients.cast<double>().squaredNorm();
  // Full rank: n' = n, or one cluster per point, or no parameters at all.
  std::map<std::string, std::int64_t> full;
  if (fixture.has("components"))
    full = {{"components", s.dimension()}, {"clusters", 4}};
  else if (fixture.has("clusters"))
    full = {{"clusters", s.vertices()}};
  KIT_CHECK_AT_MOST(kit, se(s, fixture.make(full)->encode(s, nullptr)), 1e-10 * energy);
}

static void compressor_check_2(Kit& kit) {
  Fixture fixture(kit);
  const TransferSignal s = test_signal();
  if (fixture.has("components")) {
    double previous = INFINITY;
    for (std::int64_t n : {0, 1, 2, 4, 8, 16}) {
      const double e =
          se(s, fixture.make({{"components", n}, {"clusters", 6}})->encode(s, nullptr));
      KIT_INFO(kit, "components " << n);
      KIT_CHECK_AT_MOST(kit, e, previous * (1 + 1e-9) + 1e-12);
      previous = e;
    }
  }
  if (fixture.has("clusters")) {
    double previous = INFINITY;
    for (std::int64_t k : {1, 3, 12, 48, 240}) {
      const double e =
          se(s, fixture.make({{"clusters", k}, {"components", 1}})->encode(s, nullptr));
      KIT_INFO(kit, "clusters " << k);
      KIT_CHECK_AT_MOST(kit, e,
                        previous * 1.01 + 1e-12);  // k-means local optima may reverse by a hair
      previous = e;
    }
  }
}

static void compressor_check_3(Kit& kit) {
  Fixture fixture(kit);
  const TransferSignal s = test_signal();
  const CompressedTransfer a = fixture.make()->encode(s, nullptr),
                           b = fixture.make()->encode(s, nullptr);
  KIT_CHECK(kit, a.cluster_of_vertex == b.cluster_of_vertex);
  KIT_CHECK(kit, a.weights == b.weights);
  KIT_CHECK(kit, a.means == b.means);
}

static void compressor_check_4(Kit& kit) {
  Fixture fixture(kit);
  TransferSignal same;
  same.coefficients = MatrixXfRow::Constant(20, 16, 0.25f);
  TransferSignal one;
  one.coefficients = MatrixXfRow::Constant(1, 16, -1.f);
  TransferSignal few = test_signal(5);  // fewer points than clusters and than n'
  for (const TransferSignal* s : {&same, &one, &few}) {
    const CompressedTransfer c =
        fixture.make({{"clusters", 8}, {"components", 24}})->encode(*s, nullptr);
    KIT_REQUIRE_NOTHROW(kit, c.validate(s->vertices()));
    KIT_CHECK(kit, c.decode().allFinite());
    KIT_CHECK_AT_MOST(kit, se(*s, c), 1e-10 * (1 + s->coefficients.cast<double>().squaredNorm()));
  }
}

static void compressor_check_5(Kit& kit) {
  Fixture fixture(kit);
  TransferSignal s = test_signal();
  if (fixture.make()->exact()) {  // an exact compressor stores the signal as it is, NaN included
    s.coefficients(17, 3) = NAN;
    MatrixXfRow decoded = fixture.make()->encode(s, nullptr).decode();
    KIT_CHECK(kit, std::isnan(decoded(17, 3)));
    decoded.row(17).setZero();  // the NaN spreads through vertex 17's reconstruction
    s.coefficients.row(17).setZero();
    KIT_CHECK(kit, decoded == s.coefficients);
    return;
  }
  s.coefficients(17, 3) = NAN;
  KIT_CHECK_THROWS_WITH(kit, fixture.make()->encode(s, nullptr), "vertex 17");
  s.coefficients(17, 3) = INFINITY;
  KIT_CHECK_THROWS_WITH(kit, fixture.make()->encode(s, nullptr), "vertex 17");
}

std::vector<Check> compressor_checks() {
  return {
      {"the compressed form is consistent and finite", "[conformance]", compressor_check_0},
      {"exact at full rank", "[conformance]", compressor_check_1},
      {"squared error does not grow with the budget", "[conformance]", compressor_check_2},
      {"deterministic for a seed", "[conformance]", compressor_check_3},
      {"degenerate inputs give a valid form, never NaN", "[conformance][extremes]",
       compressor_check_4},
      {"NaN or Inf input is refused naming the vertex", "[conformance][extremes]",
       compressor_check_5},
  };
}

}  // namespace prt::conformance
