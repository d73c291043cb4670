// Conformance checks run over every basis plug-in (one ctest entry each):
// orthonormality if claimed, native quadrature against the domain's measure
// and an independent rule, projection/reconstruction round trip, linearity,
// every declared capability tested and every undeclared one absent, every
// boolean and choice parameter varied, save/load round trip, extreme inputs.
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <random>
#include <sstream>

#include "kit.hpp"
#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/brdf.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/error.hpp"
#include "prt/hemisphere.hpp"
#include "prt/mesh.hpp"
#include "prt/quadrature.hpp"
#include "prt/registry.hpp"
#include "prt/transport.hpp"
#include "scenes.hpp"
#include "thread_communicator.hpp"

namespace prt::conformance {

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
  explicit Fixture(Kit& kit) : registry(kit.registry) {
    Params params;
    basis = fitted(registry.create<Basis>(kit.plugin, params));
    set = basis->native_directions().value_or(gauss_product_sphere(64));
  }
  PluginRegistry& registry;
  std::shared_ptr<Basis> basis;
  // The basis's own exact rule, or one exact for spherical polynomials of degree < 128.
  DirectionSet set;
};

Eigen::MatrixXd random_coefficients(int functions, int size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd c(functions, size);
  for (auto& x : c.reshaped()) x = g(rng);
  return c;
}

}  // namespace

static void basis_check_0(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  Directions extremes(6, 3);
  extremes << 0, 0, 1, 0, 0, -1, 1, 0, 0, 0, 1, 0, 1e-12, 0, 1, 0, -1e-12, -1;
  extremes.row(4).normalize(), extremes.row(5).normalize();
  const Eigen::MatrixXd v = basis->evaluate(extremes);
  KIT_CHECK_EQUAL(kit, v.rows(), 6);
  KIT_CHECK_EQUAL(kit, v.cols(), basis->size());
  KIT_CHECK(kit, v.allFinite());
}

static void basis_check_1(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  if (!basis->orthonormal()) return;
  const Eigen::MatrixXd y = basis->evaluate(set.directions);
  const Eigen::MatrixXd gram = y.transpose() * set.weights.asDiagonal() * y;
  const int n = basis->size();
  KIT_CHECK_AT_MOST(kit, (gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-9);
}

static void basis_check_2(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const Eigen::MatrixXd c = random_coefficients(4, basis->size(), 1);
  const Eigen::MatrixXd samples = c * basis->evaluate(set.directions).transpose();
  const Eigen::MatrixXd projected = basis->project(samples, set);
  KIT_CHECK_AT_MOST(kit, (projected - c).norm() / c.norm(), 1e-9);
}

static void basis_check_3(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const Eigen::MatrixXd f = random_coefficients(2, set.size(), 2);
  const Eigen::MatrixXd pf = basis->project(f, set);
  const Eigen::MatrixXd combined = basis->project(3.0 * f.row(0) - 0.5 * f.row(1), set);
  KIT_CHECK_AT_MOST(kit, (combined - (3.0 * pf.row(0) - 0.5 * pf.row(1))).norm(), 1e-9 * pf.norm());
  for (double scale : {1e-6, 1e6}) {
    const Eigen::MatrixXd scaled = basis->project(scale * f, set);
    KIT_REQUIRE(kit, scaled.allFinite());
    KIT_CHECK_AT_MOST(kit, (scaled / scale - pf).norm(), 1e-12 * pf.norm());
  }
  KIT_CHECK(kit,
            basis->project(Eigen::MatrixXd::Zero(1, set.size()), set).cwiseAbs().maxCoeff() == 0.0);
  // A constant function (every basis must cope, even if it is not in the span).
  const Eigen::MatrixXd constant =
      basis->project(Eigen::MatrixXd::Constant(1, set.size(), 2.5), set);
  KIT_CHECK(kit, constant.allFinite());
  KIT_CHECK(kit, constant.cwiseAbs().maxCoeff() > 0);
}

namespace {

double domain_measure(const Basis& b) {
  return b.domain() == Domain::hemisphere ? 2 * M_PI : 4 * M_PI;
}

// An independent rule over the basis's domain: a 200k-point Fibonacci sphere
// (equal weights), lower half weighted 0 for hemisphere bases.
DirectionSet independent_rule(const Basis& b) {
  DirectionSet set = DirectionSet::fibonacci(200000);
  if (b.domain() == Domain::hemisphere)
    for (Eigen::Index k = 0; k < set.size(); ++k)
      if (set.directions(k, 2) < 0) set.weights[k] = 0;
  return set;
}

// Integrals of every basis function over a rule, in blocks of points.
Eigen::RowVectorXd integrals(const Basis& b, const DirectionSet& set) {
  Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(b.size());
  for (Eigen::Index start = 0; start < set.size(); start += 8192) {
    const Eigen::Index count = std::min<Eigen::Index>(8192, set.size() - start);
    sum += set.weights.segment(start, count).transpose() *
           b.evaluate(set.directions.middleRows(start, count));
  }
  return sum;
}

}  // namespace

static void basis_check_4(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const auto native = basis->native_directions();
  if (!native) return;  // the kit then uses its own exact sphere rule
  KIT_INFO(kit,
           "weights sum to " << native->weights.sum() << "; the "
                             << (basis->domain() == Domain::hemisphere ? "hemisphere" : "sphere")
                             << " measures " << domain_measure(*basis));
  KIT_CHECK_AT_MOST(kit, std::abs(native->weights.sum() - domain_measure(*basis)),
                    1e-9 * domain_measure(*basis));
  KIT_CHECK(kit, native->weights.minCoeff() >= 0);
  KIT_CHECK(kit, native->directions.rowwise().norm().isApprox(Eigen::VectorXd::Ones(native->size()),
                                                              1e-9));
  if (basis->domain() == Domain::hemisphere)
    KIT_CHECK(kit, native->directions.col(2).minCoeff() >= 0);
}

static void basis_check_5(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  // Integrals of the basis functions over the kit's rule and over the
  // plug-in's own: a rule whose weights are off (even consistently with the
  // functions) or a function defined outside its domain shows here.
  const DirectionSet independent = independent_rule(*basis);
  const Eigen::RowVectorXd expected = integrals(*basis, independent);
  const Eigen::RowVectorXd own = integrals(*basis, set);
  const double scale = std::max(expected.norm(), 1e-3 * std::sqrt(domain_measure(*basis)));
  KIT_INFO(kit,
           "function integrals differ by " << (own - expected).norm() / scale << " (relative)");
  KIT_CHECK_AT_MOST(kit, (own - expected).norm(), 0.02 * scale);
  if (basis->orthonormal() && basis->size() <= 100) {
    // The Gram matrix on the independent rule (accurate to ~1e-3 for smooth bases).
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(basis->size(), basis->size());
    for (Eigen::Index start = 0; start < independent.size(); start += 8192) {
      const Eigen::Index count = std::min<Eigen::Index>(8192, independent.size() - start);
      const Eigen::MatrixXd y = basis->evaluate(independent.directions.middleRows(start, count));
      gram += y.transpose() * independent.weights.segment(start, count).asDiagonal() * y;
    }
    const double off =
        (gram - Eigen::MatrixXd::Identity(basis->size(), basis->size())).cwiseAbs().maxCoeff();
    KIT_INFO(kit, "independent Gram matrix is off the identity by " << off);
    KIT_CHECK_AT_MOST(kit, off, 0.02);
  }
}

static void basis_check_6(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  if (!basis->can_rotate()) {
    // Not declared: asked anyway, it says so rather than returning something.
    KIT_CHECK_THROWS_WITH(kit, basis->rotation_matrix(Eigen::Matrix3d::Identity()), "");
    return;
  }
  const Eigen::Matrix3d a =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d b = Eigen::AngleAxisd(-1.9, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::MatrixXd ra = basis->rotation_matrix(a), rb = basis->rotation_matrix(b);
  KIT_CHECK_AT_MOST(kit, (ra * rb - basis->rotation_matrix(a * b)).cwiseAbs().maxCoeff(), 1e-10);
  // Rotating coefficients equals projecting f(A^T d).
  const Eigen::VectorXd c = random_coefficients(1, basis->size(), 3).transpose();
  const Directions back = set.directions * a;
  const Eigen::RowVectorXd samples = (basis->evaluate(back) * c).transpose();
  const Eigen::VectorXd reprojected = basis->project(samples, set).transpose();
  KIT_CHECK_AT_MOST(kit, (ra * c - reprojected).norm() / c.norm(), 1e-9);
  // A rotation of functions keeps their norms: an orthonormal basis's
  // rotation matrix is orthogonal.
  if (basis->orthonormal()) {
    const int n = basis->size();
    KIT_CHECK(kit,
              (ra.transpose() * ra - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff() < 1e-9);
  }
}

static void basis_check_7(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const std::vector<int> bands = basis->coefficient_bands();
  if (!bands.empty()) {
    KIT_CHECK_EQUAL(kit, bands.size(), basis->size());
    KIT_CHECK(kit, *std::min_element(bands.begin(), bands.end()) >= 0);
    KIT_CHECK(kit, std::is_sorted(bands.begin(), bands.end()));
    if (basis->can_rotate()) {  // a rotation never mixes bands
      const Eigen::MatrixXd r = basis->rotation_matrix(
          Eigen::AngleAxisd(1.1, Eigen::Vector3d(3, 1, 2).normalized()).toRotationMatrix());
      for (int i = 0; i < basis->size(); ++i)
        for (int j = 0; j < basis->size(); ++j)
          if (bands[i] != bands[j]) KIT_CHECK_AT_MOST(kit, std::abs(r(i, j)), 1e-12);
    }
  }
  if (!basis->can_fit()) {  // fitting a basis that does not fit changes nothing
    const Mesh scene = test::sphere_over_plane();
    const DirectionSet lattice = DirectionSet::cubemap(4);
    const TransportResult r = test::trace_visibility_only(scene, lattice);
    const Eigen::MatrixXd before = basis->evaluate(set.directions);
    basis->fit({&scene, &lattice, &r.visibility});
    KIT_CHECK(kit, basis->evaluate(set.directions) == before);
  }
  KIT_CHECK(kit, basis->approximation_terms() >= 0);
  KIT_CHECK_AT_MOST(kit, basis->approximation_terms(), basis->size());
  if (!basis->has_fast_projection(set)) {  // the default projection is the matrix's
    const Eigen::MatrixXd f = random_coefficients(2, set.size(), 9);
    KIT_CHECK_AT_MOST(kit, (basis->project(f, set) - f * basis->projection_matrix(set)).norm(),
                      1e-12 * f.norm() * basis->projection_matrix(set).norm());
  }
}

static void basis_check_8(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const BasisState state = basis->save();
  Params fresh_params;
  auto fresh = registry.create<Basis>(kit.plugin, fresh_params);
  fresh->load(state);
  KIT_CHECK_EQUAL(kit, fresh->size(), basis->size());
  KIT_CHECK(kit, fresh->evaluate(set.directions) == basis->evaluate(set.directions));
}

static void basis_check_9(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const ParamSchema schema = registry.find(PluginKind::basis, kit.plugin).schema();
  Directions extremes(4, 3);
  extremes << 0, 0, 1, 0, 0, -1, 1, 0, 0, 0.6, 0, 0.8;
  for (const auto& spec : schema.specs) {
    if (spec.type != ParamType::integer || std::string(spec.name) == "seed") continue;
    for (double value : {spec.min, spec.max}) {
      KIT_INFO(kit, spec.name << " = " << value);
      Params p;
      p.set(spec.name, static_cast<std::int64_t>(value));
      std::shared_ptr<Basis> b;
      try {
        b = fitted(registry.create<Basis>(kit.plugin, p));
      } catch (const Error& e) {
        // A value the schema allows may still be refused with a clear message
        // (e.g. a resolution that is not a power of 2) -- but never crash.
        KIT_CHECK(kit, std::string(e.what()).find(spec.name) != std::string::npos);
        continue;
      }
      const Eigen::MatrixXd v = b->evaluate(extremes);
      KIT_CHECK(kit, v.allFinite());
      KIT_CHECK_EQUAL(kit, v.cols(), b->size());
      if (value == spec.min) {  // small enough for the round trip
        const DirectionSet native = b->native_directions().value_or(gauss_product_sphere(64));
        const Eigen::MatrixXd c = random_coefficients(2, b->size(), 5);
        const Eigen::MatrixXd back =
            b->project(c * b->evaluate(native.directions).transpose(), native);
        KIT_CHECK_AT_MOST(kit, (back - c).norm(), 1e-8 * c.norm());
      }
    }
  }
}

namespace {

// Every combination of the schema's boolean and choice values (at most 64;
// other parameters at their defaults).
std::vector<std::vector<std::pair<std::string, ParamValue>>> combinations(
    const ParamSchema& schema) {
  std::vector<std::vector<std::pair<std::string, ParamValue>>> out{{}};
  for (const auto& spec : schema.specs) {
    std::vector<ParamValue> values;
    if (spec.type == ParamType::boolean) values = {false, true};
    if (spec.type == ParamType::string)
      for (const std::string& choice : choices_of(spec)) values.push_back(choice);
    if (values.empty()) continue;
    std::vector<std::vector<std::pair<std::string, ParamValue>>> next;
    for (const auto& partial : out)
      for (const auto& v : values) {
        next.push_back(partial);
        next.back().emplace_back(spec.name, v);
      }
    out = std::move(next);
    if (out.size() > 64) out.resize(64);
  }
  return out;
}

}  // namespace

static void basis_check_10(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const ParamSchema schema = registry.find(PluginKind::basis, kit.plugin).schema();
  for (const auto& combination : combinations(schema)) {
    if (combination.empty()) continue;
    std::string label;
    Params p;
    for (const auto& [key, value] : combination) {
      p.set(key, value);
      const bool* flag = std::get_if<bool>(&value);
      const std::string* text = std::get_if<std::string>(&value);
      label += key + "=" + (flag ? (*flag ? "true" : "false") : text ? *text : "?") + " ";
    }
    KIT_INFO(kit, "parameters: " << label);
    std::shared_ptr<Basis> b;
    try {
      b = fitted(registry.create<Basis>(kit.plugin, p));
    } catch (const Error& e) {
      // A refused combination must say which parameter (params.fail does).
      bool named = false;
      for (const auto& [key, value] : combination)
        named = named || std::string(e.what()).find("\"" + key + "\"") != std::string::npos;
      KIT_INFO(kit, "refused with: " << e.what());
      KIT_CHECK(kit, named);
      continue;
    }
    const DirectionSet native = b->native_directions().value_or(gauss_product_sphere(64));
    const Eigen::MatrixXd y = b->evaluate(native.directions);
    KIT_REQUIRE(kit, b->size() > 0);
    KIT_CHECK_EQUAL(kit, y.cols(), b->size());  // size() must follow every parameter
    KIT_CHECK(kit, y.allFinite());
    if (y.cols() != b->size()) continue;
    if (b->orthonormal()) {
      const Eigen::MatrixXd gram = y.transpose() * native.weights.asDiagonal() * y;
      KIT_CHECK(
          kit,
          (gram - Eigen::MatrixXd::Identity(b->size(), b->size())).cwiseAbs().maxCoeff() < 1e-9);
    }
    // Projection (by whichever method the parameters choose) gives one
    // finite coefficient per function.
    const Eigen::MatrixXd p_matrix = b->projection_matrix(native);
    KIT_CHECK_EQUAL(kit, p_matrix.cols(), b->size());
    KIT_CHECK(kit, p_matrix.allFinite());
  }
}

// A basis that fits distributed (prt-mpi) must fit, on every rank holding a
// shard of the bits, the basis one process fits to all of them, bit for bit:
// a sum over vertices left to one rank's shard, or added in an order that
// depends on the ranks, shows here. Three segments of vertices, the last
// short; two and three simulated ranks.
static void basis_check_11(Kit& kit) {
  Params params;
  auto one = kit.registry.create<Basis>(kit.plugin, params);
  if (!one->can_fit_distributed()) return;
  KIT_REQUIRE(kit, one->can_fit());
  const Mesh scene = test::sphere_over_plane(5, 100);
  const DirectionSet lattice = DirectionSet::cubemap(4);
  const TransportResult r = test::trace_visibility_only(scene, lattice);
  one->fit({&scene, &lattice, &r.visibility});
  const BasisState want = one->save();
  const auto total = static_cast<Eigen::Index>(scene.vertex_count());
  for (int ranks : {2, 3}) {
    std::vector<std::shared_ptr<Basis>> bases;  // made here: the registry is not shared
    for (int rank = 0; rank < ranks; ++rank)
      bases.push_back(kit.registry.create<Basis>(kit.plugin, params));
    std::vector<std::string> errors(static_cast<std::size_t>(ranks));
    test::run_on_ranks(ranks, [&](const Communicator& comm) {
      const Shard shard = shard_of(total, comm.rank(), ranks);
      const VisibilityBits bits =
          test::shard_bits(r.visibility, std::size_t(shard.first), std::size_t(shard.last));
      try {
        bases[std::size_t(comm.rank())]->fit(
            {&scene, &lattice, &bits, prt::parts_over(comm, shard)});
      } catch (const std::exception& e) {
        errors[std::size_t(comm.rank())] = e.what();
      }
    });
    for (int rank = 0; rank < ranks; ++rank) {
      KIT_INFO(kit, "rank " << rank << " of " << ranks << " (vertices "
                            << shard_of(total, rank, ranks).first << "-"
                            << shard_of(total, rank, ranks).last << " of " << total << ")");
      KIT_INFO(kit, "its fit threw: " << errors[std::size_t(rank)]);
      KIT_CHECK(kit, errors[std::size_t(rank)].empty());
      if (!errors[std::size_t(rank)].empty()) continue;
      const BasisState got = bases[std::size_t(rank)]->save();
      KIT_CHECK(kit, got.matrices.size() == want.matrices.size());
      for (const auto& [name, matrix] : want.matrices) {
        const auto it = got.matrices.find(name);
        const bool same = it != got.matrices.end() && it->second.rows() == matrix.rows() &&
                          it->second.cols() == matrix.cols() && it->second == matrix;
        KIT_INFO(kit, "fitted state \"" << name
                                        << "\" against the one-process fit's (differs when a sum "
                                           "over vertices does not go through segment_sum)");
        KIT_CHECK(kit, same);
      }
    }
  }
}

// The PRT identity: relighting, the transfer's coefficients dotted with the
// light as the framework hands it over (G l, prt/basis_metric.hpp), equals
// the integral of light times transfer. T lies in the span (T = sum c_i B_i),
// L is a smooth function that does not (two exponential lobes and a
// constant), so int L T = int P(L) T holds exactly and the quadrature on the
// kit's rule is the reference. A basis whose projection is not least squares
// for its metric, or that claims orthonormality it lacks, relights wrong and
// fails here with both numbers.
static void basis_check_12(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  const int n = basis->size();
  const Eigen::MatrixXd values = basis->evaluate(set.directions);  // s x n
  const Eigen::MatrixXd c = random_coefficients(3, n, 12);
  const Eigen::MatrixXd transfer = c * values.transpose();  // 3 x s
  Eigen::MatrixXd light(3, set.size());
  const Eigen::Vector3d axes[3] = {Eigen::Vector3d(0.3, 0.5, 0.81).normalized(),
                                   Eigen::Vector3d(-0.7, 0.1, 0.2).normalized(),
                                   Eigen::Vector3d(0.05, -0.9, 0.4).normalized()};
  for (int j = 0; j < 3; ++j)
    for (Eigen::Index k = 0; k < set.size(); ++k) {
      const Eigen::Vector3d d = set.directions.row(k).transpose();
      light(j, k) =
          std::exp(2.0 * axes[j].dot(d)) + 0.5 * std::exp(3.0 * axes[(j + 1) % 3].dot(d)) + 0.3;
    }
  const Eigen::MatrixXd t = basis->project(transfer, set), l = basis->project(light, set);
  const BasisMetric metric = basis_metric(*basis);
  const Eigen::MatrixXd g = metric.identity ? Eigen::MatrixXd::Identity(n, n) : metric.gram;
  for (int j = 0; j < 3; ++j) {
    const double relit = t.row(j) * g * l.row(j).transpose();
    const double expected =
        (transfer.row(j).array() * light.row(j).array() * set.weights.transpose().array()).sum();
    // Cauchy-Schwarz's bound on |int L T| sets the scale of the tolerance.
    const double scale =
        std::sqrt((transfer.row(j).array().square() * set.weights.transpose().array()).sum() *
                  (light.row(j).array().square() * set.weights.transpose().array()).sum());
    KIT_INFO(kit, "light " << j << ": t . G l = " << relit << ", int L T by quadrature = "
                           << expected << ", tolerance 1e-6 x " << scale
                           << (metric.identity ? " (G = I: the basis says it is orthonormal)"
                                               : " (G from the basis's rule)"));
    KIT_CHECK_LESS(kit, std::abs(relit - expected), 1e-6 * scale);
  }
}

namespace {

// View directions for the exit role: uniform over the hemisphere, and
// grazing ones (z = 1e-3, 1e-2, 0.05: the renderer keeps z >= 1e-3).
Directions exit_view_directions() {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> uniform(0, 1);
  const double grazing[] = {1e-3, 1e-2, 0.05};
  Directions views(256 + 3 * 32, 3);
  for (Eigen::Index k = 0; k < views.rows(); ++k) {
    const double z = k < 256 ? uniform(rng) : grazing[(k - 256) / 32];
    const double phi = 2 * M_PI * uniform(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
    views.row(k) << r * std::cos(phi), r * std::sin(phi), z;
  }
  return views;
}

// Exit radiance toward each view v: int_H L(s) rho(s, v) s_z ds on the rule.
Eigen::VectorXd exit_radiance(const Brdf& brdf, const DirectionSet& incident,
                              const Eigen::VectorXd& light, const Directions& views) {
  Eigen::VectorXd out(views.rows());
  for (Eigen::Index v = 0; v < views.rows(); ++v) {
    double sum = 0;
    for (Eigen::Index k = 0; k < incident.size(); ++k) {
      const Eigen::Vector3d s = incident.directions.row(k).transpose();
      sum += incident.weights[k] * light[k] * brdf.evaluate(s, views.row(v).transpose()) * s.z();
    }
    out[v] = sum;
  }
  return out;
}

}  // namespace

// The exit role (a hemisphere basis, `[exit]` of a glossy scene): the exit
// radiance of a glossy Phong lobe under a smooth light, projected as the
// glossy bake projects it (projection_matrix on the framework's hemisphere
// rule) and evaluated toward view directions as the renderer does, grazing
// ones included, against the BRDF integral itself. The lobe is not in any
// finite span, so the yardstick is the best the basis can do: the kit's own
// least squares over the same rule, with the basis's values; the plug-in's
// error must be within 2x that (plus 1e-6 of the radiance's scale).
static void basis_check_13(Kit& kit) {
  Fixture fixture(kit);
  [[maybe_unused]] auto& [registry, basis, set] = fixture;
  if (basis->domain() != Domain::hemisphere) return;  // a light basis only: check 12
  Brdf brdf;
  brdf.model = BrdfModel::phong;
  brdf.kd = 0.4, brdf.ks = 0.6, brdf.exponent = 12;  // the glossy example's lobe
  const DirectionSet incident = hemisphere::upper_quadrature(64);
  Eigen::VectorXd light(incident.size());
  const Eigen::Vector3d axis = Eigen::Vector3d(0.5, -0.3, 0.6).normalized();
  for (Eigen::Index k = 0; k < incident.size(); ++k)
    light[k] = std::exp(3.0 * axis.dot(incident.directions.row(k).transpose())) + 0.2;
  const DirectionSet rule = hemisphere::upper_quadrature(48);  // GlossyOperator's default
  const Directions views = exit_view_directions();
  const Eigen::VectorXd on_rule = exit_radiance(brdf, incident, light, rule.directions);
  const Eigen::VectorXd expected = exit_radiance(brdf, incident, light, views);
  const Eigen::MatrixXd at_views = basis->evaluate(views);
  // The plug-in's projection, as the bake uses it.
  const Eigen::VectorXd coefficients = basis->projection_matrix(rule).transpose() * on_rule;
  const Eigen::VectorXd relit = at_views * coefficients;
  // The kit's least squares in the same span (SVD, relative cut-off 1e-10).
  const Eigen::MatrixXd values = basis->evaluate(rule.directions);
  const Eigen::VectorXd root = rule.weights.cwiseSqrt();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(root.asDiagonal() * values,
                                        Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(1e-10);
  const Eigen::VectorXd best = at_views * svd.solve(root.cwiseProduct(on_rule));
  Eigen::Index worst = 0;
  const double error = (relit - expected).cwiseAbs().maxCoeff(&worst);
  const double best_error = (best - expected).cwiseAbs().maxCoeff();
  const double scale = expected.cwiseAbs().maxCoeff();
  KIT_INFO(kit, "exit radiance of a Phong lobe (exponent 12) toward "
                    << views.rows() << " view directions (z down to 1e-3): largest error " << error
                    << " at z = " << views(worst, 2) << " (relit " << relit[worst]
                    << ", BRDF integral " << expected[worst] << "); the least squares in the "
                    << "same span errs by at most " << best_error
                    << "; tolerance 2 x that + 1e-6 x " << scale);
  KIT_CHECK(kit, relit.allFinite());
  KIT_CHECK_LESS(kit, error, 2 * best_error + 1e-6 * scale);
}

std::vector<Check> basis_checks() {
  return {
      {"basis values are finite everywhere, poles included", "[conformance]", basis_check_0},
      {"an orthonormal basis has an identity Gram matrix", "[conformance]", basis_check_1},
      {"projection reconstructs functions in the span", "[conformance]", basis_check_2},
      {"projection is linear and scales from 1e-6 to 1e6", "[conformance]", basis_check_3},
      {"native quadrature weights integrate 1 to the domain's measure", "[conformance]",
       basis_check_4},
      {"the basis agrees with an independent quadrature", "[conformance]", basis_check_5},
      {"rotation is consistent with re-projection and composes", "[conformance]", basis_check_6},
      {"declared capabilities hold, undeclared ones are absent", "[conformance]", basis_check_7},
      {"saved state restores an identical basis", "[conformance]", basis_check_8},
      {"every integer parameter works at its smallest and largest value", "[conformance][extremes]",
       basis_check_9},
      {"every boolean and choice parameter value gives a consistent basis",
       "[conformance][parameters]", basis_check_10},
      {"a distributed fit equals the one-process fit bit for bit", "[conformance][distributed]",
       basis_check_11},
      {"relighting equals the integral of light times transfer", "[conformance][metric]",
       basis_check_12},
      {"exit radiance equals the BRDF integral toward every view, grazing ones included",
       "[conformance][metric]", basis_check_13},
  };
}

}  // namespace prt::conformance
