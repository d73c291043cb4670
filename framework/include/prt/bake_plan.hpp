// The bake plan: what a bake will do, decided and validated from the scene
// before any ray is traced.
#pragma once
#include <functional>
#include <memory>
#include <string>

#include "prt/bake_file.hpp"
#include "prt/basis.hpp"
#include "prt/brdf.hpp"
#include "prt/compressor.hpp"
#include "prt/glossy.hpp"
#include "prt/plugin_record.hpp"
#include "prt/registry.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/scene.hpp"

namespace prt {

// Everything a bake will do, decided and validated from the scene before any
// ray is traced: the plug-ins (created, so their parameters are checked),
// what to keep, fit, project and compress.
// A value: nothing a bake does changes it. A basis fitted to the scene's rays
// (fit) is a new object, made by new_basis and returned by stage 2
// (TransferOutcome::basis); the stages after it take with_basis(fitted).
struct BakePlan {
  std::shared_ptr<const Basis> basis;  // light basis (a sphere basis)
  std::shared_ptr<const Basis> exit;   // glossy only: exit basis (a hemisphere basis)
  std::shared_ptr<const Compressor> compressor;
  // A fresh light basis with the scene's parameters, to fit or to load a
  // kept fitted state into.
  std::function<std::shared_ptr<Basis>()> new_basis;
  PluginRecord basis_record, exit_record, compressor_record;
  bool glossy = false, subsurface = false, fit = false;
  bool probes = false;  // [receivers] kind = "probes": exit is the incident basis
  bool texels = false;  // [receivers] kind = "texels": rows are the atlas's texels
  // The surfaces rays meet when the rows are not the mesh's own vertices
  // (texels: the scene's mesh); null: the rows' mesh itself.
  const Mesh* occluders = nullptr;
  const Mesh& surfaces(const Mesh& rows) const { return occluders ? *occluders : rows; }
  int bounces = 0;
  double bounce_albedo = 1;
  int sparse_terms = 0;          // > 0: the basis's own sparse approximation replaces compression
  bool keep_visibility = false;  // fitting and glossy matrices need the bits
  bool shadowed = true;
  // Glossy: the BRDF and its incident band limit.
  Brdf brdf;
  int incident_order = 0;
  bool least_squares = true;
  double cutoff = 1e-10;
  GlossyMethod glossy_method = GlossyMethod::rotate_sh;
  GlossyOperator glossy_operator;  // made by plan_bake
  SubsurfaceMaterial subsurface_material;
  // Colour channels that need transfers of their own (one group: the scene's
  // channels agree, and the fields above are its material).
  MaterialChannels channels;

  // The same plan with `fitted` as its light basis.
  BakePlan with_basis(std::shared_ptr<const Basis> fitted) const {
    BakePlan copy = *this;
    copy.basis = std::move(fitted);
    return copy;
  }
};
BakePlan plan_bake(const SceneSpec& scene, PluginRegistry& registry);

// Rows of each transfer's matrix: the exit basis's (glossy), the incident
// basis's (probes), else 1.
int exit_rows(const BakePlan& plan);

// What a scene's bake depends on (scene text, mesh bytes, plug-ins, format):
// the key of its checkpoint.
std::string bake_key(const SceneSpec& scene, const BakePlan& plan);

// Refuses (located at the key) a `components` budget, given by the user, larger
// than the transfer's `dimension` coefficients per vertex; a default beyond it
// is used as far as it goes (the compressor warns).
void refuse_budget_beyond_signal(const Params& params, Eigen::Index dimension,
                                 const std::string& compressor);

// The rendered metric of the plan's bases (identity for orthonormal ones and
// sparse approximations): what compression minimises.
RenderedMetric rendered_metric(const BakePlan& plan);

}  // namespace prt
