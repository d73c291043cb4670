// The bake plan: everything a bake will do, decided and checked from the scene
// before any ray (plug-ins created, domains checked against their roles).
#include "prt/bake_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/compressor.hpp"
#include "prt/glossy.hpp"
#include "prt/log.hpp"
#include "prt/rendered_metric.hpp"

namespace prt {

namespace {

// "sphere" / "hemisphere" with the role each serves, for domain errors.
std::string domain_error(const PluginChoice& choice, const char* section, Domain wanted) {
  const bool sphere = wanted == Domain::sphere;
  return "[" + std::string(section) + "] basis \"" + choice.name + "\" is defined over the " +
         (sphere ? "hemisphere of a local frame" : "whole sphere") + ", but this role needs a " +
         (sphere ? "sphere" : "hemisphere") +
         " basis: the light basis ([basis]) carries source light and diffuse transfer over the "
         "sphere; the exit basis ([exit], glossy only) carries exit radiance over each vertex's "
         "upper hemisphere";
}

PluginRecord record_of(const PluginChoice& choice, PluginRegistry& registry, PluginKind kind) {
  return {choice.name, registry.find(kind, choice.name).info.version, choice.params.describe()};
}

}  // namespace

namespace {

// What the direction set really is, and whether it can resolve the basis:
// a cube map rounds `rays` to 6 R^2, and fewer directions than twice the
// basis's functions alias (unless the set is the basis's own lattice, on
// which its projection is exact).
void warn_if_under_sampled(const SceneSpec& scene, const DirectionSet& set, const Basis& basis,
                           const std::string& name) {
  const std::string where = scene.transport.location(keys::transport::rays.name()).str() + ": ";
  const auto rays = keys::transport::rays(scene.transport);
  if (set.kind == "cubemap" && set.size() != rays) {
    const int r = static_cast<int>(std::lround(std::sqrt(set.size() / 6.0)));
    log_warning_once(where + "rays = " + std::to_string(rays) + " makes a 6 x " +
                     std::to_string(r) + " x " + std::to_string(r) + " cube map: " +
                     std::to_string(set.size()) + " directions (a cube map has 6 R^2)");
  }
  const auto native = basis.native_directions();
  const bool own_lattice = native && native->kind == set.kind && native->size() == set.size();
  if (!own_lattice && set.size() < 2 * Eigen::Index(basis.size()))
    log_warning_once(where + std::to_string(set.size()) + " directions for basis \"" + name +
                     "\"'s " + std::to_string(basis.size()) +
                     " functions: fewer than twice as many, so the projection aliases; raise "
                     "[transport] rays to " +
                     std::to_string(2 * basis.size()) + " or more");
}

// orthonormal() is a claim the relight relies on (it then applies no
// metric): checked on the basis's rule before any ray, for bases small
// enough that G costs milliseconds (n <= 400) and not fitted to the bake.
void check_orthonormal_claim(const Basis& basis, const PluginChoice& choice) {
  if (!basis.orthonormal() || basis.can_fit() || basis.size() > 400) return;
  const Eigen::MatrixXd g = gram_matrix(basis);
  const double off = (g - Eigen::MatrixXd::Identity(g.rows(), g.cols())).cwiseAbs().maxCoeff();
  if (!(off <= 1e-6)) {
    char text[120];
    std::snprintf(text, sizeof text, "%.3g", off);
    throw Error(choice.where, "basis \"" + choice.name +
                                  "\" says it is orthonormal, but its Gram matrix differs from "
                                  "the identity by " +
                                  text +
                                  " on its own rule; relighting with it would be wrong. Return "
                                  "false from orthonormal() and the framework applies its metric");
  }
}

// Glossy transfer's part of the plan: the exit basis (a fixed hemisphere
// basis), the BRDF and its operator, made before any ray (it depends only on
// the BRDF and the exit basis).
void plan_glossy(const SceneSpec& scene, PluginRegistry& registry, BakePlan& plan) {
  PluginChoice exit = scene.exit;
  plan.exit = registry.create<Basis>(exit.name, exit.params, exit.where);
  plan.exit_record = record_of(scene.exit, registry, PluginKind::basis);
  if (plan.exit->domain() != Domain::hemisphere)
    throw Error(exit.where, domain_error(exit, "exit", Domain::hemisphere));
  check_orthonormal_claim(*plan.exit, exit);
  if (plan.exit->can_fit())
    throw Error(exit.where, "[exit] basis \"" + exit.name +
                                "\" is data-driven (fits to traced visibility); an exit basis "
                                "must be fixed before the bake");
  plan.brdf = scene.brdf();
  plan.incident_order = scene.incident_order(*plan.basis);
  plan.least_squares = keys::material::projection(scene.material) == "least-squares";
  plan.cutoff = keys::material::cutoff(scene.material);
  try {
    plan.glossy_operator = GlossyOperator::make(plan.brdf, *plan.exit, plan.incident_order,
                                                plan.least_squares, plan.cutoff);
  } catch (const Error& e) {
    throw Error(exit.where, e.what());
  }
}

// Probes: the basis of the light arriving at each probe ([exit], a sphere
// basis; by default the light basis). A smaller incident basis than the
// light's keeps what diffuse receivers need (irradiance is smooth) while
// the light keeps the frequencies visibility cuts (docs/receivers.md).
void plan_probes(const SceneSpec& scene, PluginRegistry& registry, BakePlan& plan) {
  plan.probes = true;
  if (plan.fit)
    throw Error(scene.basis.where, "basis \"" + plan.basis_record.name +
                                       "\" is fitted to the visibility at vertices; probes take "
                                       "a basis that needs no fit");
  if (scene.exit.name.empty()) {
    plan.exit = plan.basis;
    plan.exit_record = plan.basis_record;
    return;
  }
  PluginChoice exit = scene.exit;
  plan.exit = registry.create<Basis>(exit.name, exit.params, exit.where);
  plan.exit_record = record_of(scene.exit, registry, PluginKind::basis);
  if (plan.exit->domain() != Domain::sphere)
    throw Error(exit.where, "[exit] basis \"" + exit.name +
                                "\" is a hemisphere basis; at probes [exit] carries the light "
                                "arriving over the whole sphere: use a sphere basis");
  check_orthonormal_claim(*plan.exit, exit);
  if (plan.exit->can_fit())
    throw Error(exit.where, "[exit] basis \"" + exit.name +
                                "\" is data-driven (fits to traced visibility); at probes use a "
                                "basis that needs no fit");
}

}  // namespace

void refuse_budget_beyond_signal(const Params& params, Eigen::Index dimension,
                                 const std::string& compressor) {
  if (!params.has("components")) return;
  const SourceLocation &at = params.location("components"), &section = params.location();
  const bool given = at.file != section.file || at.line != section.line ||
                     at.column != section.column;  // a default is located at its section
  std::int64_t components = 0;
  try {
    components = params.get_int("components");
  } catch (const Error&) {
    return;  // not an integer: not the conventional budget key
  }
  if (!given || components <= dimension) return;
  params.fail("components", "compressor \"" + compressor + "\": " + std::to_string(components) +
                                " is more than the transfer's " + std::to_string(dimension) +
                                " coefficients per vertex: each cluster would store more than "
                                "the uncompressed transfer (at most " +
                                std::to_string(dimension) + ")");
}
BakePlan plan_bake(const SceneSpec& scene, PluginRegistry& registry) {
  BakePlan plan;
  PluginChoice basis = scene.basis, compressor = scene.compressor;
  // The one way the light basis is made: the plan's, and a fresh one to fit.
  plan.new_basis = [&registry, basis] {
    Params params = basis.params;
    return registry.create<Basis>(basis.name, params, basis.where);
  };
  plan.basis = plan.new_basis();
  plan.compressor =
      registry.create<Compressor>(compressor.name, compressor.params, compressor.where);
  plan.basis_record = record_of(scene.basis, registry, PluginKind::basis);
  plan.compressor_record = record_of(scene.compressor, registry, PluginKind::compressor);
  if (plan.basis->domain() != Domain::sphere)
    throw Error(basis.where, domain_error(basis, "basis", Domain::sphere));
  scene.check_window(*plan.basis);
  check_orthonormal_claim(*plan.basis, basis);
  try {  // the direction set is cheap to make; its rays come later
    const DirectionSet set = scene.directions();
    plan.basis->check_directions(set);
    warn_if_under_sampled(scene, set, *plan.basis, basis.name);
  } catch (const Error& e) {
    throw Error(scene.transport.location(keys::transport::directions.name()), e.what());
  }
  plan.sparse_terms = plan.basis->approximation_terms();
  if (plan.sparse_terms > 0 && !plan.compressor->exact())
    throw Error(compressor.where,
                "basis \"" + basis.name +
                    "\" approximates non-linearly (keeps its largest coefficients per vertex); "
                    "that replaces compression, so use an exact compressor such as \"none\" "
                    "(not \"" +
                    compressor.name + "\")");
  plan.glossy = scene.glossy();
  plan.subsurface = keys::material::subsurface(scene.material);
  plan.bounces = static_cast<int>(keys::transport::bounces(scene.transport));
  plan.bounce_albedo = scene.bounce_albedo();
  plan.shadowed = keys::transport::shadowed(scene.transport);
  plan.fit = plan.basis->can_fit();
  if (plan.glossy) plan_glossy(scene, registry, plan);
  if (scene.probes()) plan_probes(scene, registry, plan);
  plan.texels = scene.texels();
  plan.subsurface_material = scene.subsurface();
  plan.channels = scene.channels();
  plan.keep_visibility = plan.fit || plan.glossy;
  if (plan.sparse_terms == 0)
    refuse_budget_beyond_signal(
        compressor.params,
        Eigen::Index(plan.basis->size()) * (plan.exit ? plan.exit->size() : 1) *
            Eigen::Index(std::max<std::size_t>(1, plan.channels.groups.size())),
        compressor.name);
  return plan;
}

int exit_rows(const BakePlan& plan) {
  return plan.glossy ? plan.glossy_operator.rows() : plan.probes ? plan.exit->size() : 1;
}

RenderedMetric rendered_metric(const BakePlan& plan) {
  // Sparse: the basis's own coefficients are kept. Probes: the incident
  // light's coefficients, compared as they are.
  if (plan.sparse_terms > 0 || plan.probes) return {};
  return RenderedMetric(*plan.basis, plan.glossy ? plan.exit.get() : nullptr);
}

}  // namespace prt
