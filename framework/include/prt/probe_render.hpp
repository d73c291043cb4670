// Viewing a probe bake: the light each probe receives, and every vertex of
// the scene and of its moving object shaded from the probes around it.
#pragma once
#include <memory>

#include "prt/bake_file.hpp"
#include "prt/environment.hpp"
#include "prt/probe_shading.hpp"
#include "prt/registry.hpp"
#include "prt/relighting.hpp"
#include "prt/run_options.hpp"
#include "prt/scene.hpp"

namespace prt {

// What viewing a probe bake needs, made once: the light basis, the scene's
// rays (for the leak control's visibility) and the rule of the lobes.
class ProbeRelighting {
 public:
  // Checks the bake against the scene and its plug-ins.
  ProbeRelighting(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry);
  const Basis& basis() const { return *basis_; }
  // The basis of the light arriving at probes ([exit]; the light basis by default).
  const Basis& incident_basis() const { return *incident_; }
  Eigen::MatrixX3d light(const Environment& environment) const;
  // e_p = T_p l at every probe (n x 3 each), from `transfer` (the bake's
  // compressed form or another encoding of its rows).
  std::vector<Eigen::MatrixX3d> incident(const CompressedTransfer& transfer,
                                         const Eigen::MatrixX3d& light) const;
  // The scene's interpolation ([receivers] interpolation, normal_bias).
  ProbeLookup lookup() const { return lookup_; }
  // `points` shaded from the probes (albedo 1): lobes of its normals, 8
  // probes a point, the leak control's rays against the bake's scene.
  ProbeShading shade(const Mesh& points, const std::vector<Eigen::MatrixX3d>& incident,
                     const ProbeLookup& lookup) const;
  // Its two parts, for a view that keeps them while the light turns: the
  // lobes of the points' normals, and which probes light each point.
  Eigen::MatrixXd lobes(const Mesh& points) const;
  ProbeWeights weights(const Mesh& points, const ProbeLookup& lookup) const;

 private:
  const SceneSpec& scene_;
  const BakeData& data_;
  std::shared_ptr<Basis> basis_, incident_;
  std::unique_ptr<RayCaster> caster_;
  DirectionSet lobe_rule_;
  ProbeLookup lookup_;
};

// The scene's mesh, with its [moving] object (when it has one) joined after
// its vertices: what a probe bake's image shows.
Mesh probe_scene_display(const SceneSpec& scene, const BakeData& data);

// Light projection -> light at each probe -> every displayed vertex shaded
// from its probes (albedo applied) -> the scene's renderer.
Rendered render_probes(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                       StageTimes& times, const RunOptions& options = {});

}  // namespace prt
