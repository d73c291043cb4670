// prt-view on a probe bake: the scene and its moving object shaded from the
// probes, the object moved by the keys that move a point light.
#pragma once
#include <Eigen/Core>

#include "prt/probe_render.hpp"

namespace prt::view {

class ProbeView {
 public:
  // `scene` and `data` must outlive the view.
  ProbeView(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry);
  ProbeView(const ProbeView&) = delete;
  ProbeView& operator=(const ProbeView&) = delete;

  // The scene's mesh with the moving object where it is now.
  const Mesh& display();
  // Moves the object (scene units); nothing when the scene has none.
  void move(const Eigen::Vector3f& offset);
  const Eigen::Vector3f& position() const { return position_; }
  bool has_moving() const { return has_moving_; }
  Eigen::MatrixX3d light(const Environment& environment) const {
    return relighting_.light(environment);
  }
  // Radiance of display()'s vertices (albedo applied) for `transfer` (an
  // encoding of the bake's rows) under `light`.
  Eigen::MatrixX3f radiance(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light);
  // Milliseconds of the last radiance(): the probes' light, then the shading.
  double incident_ms() const { return incident_ms_; }
  double shade_ms() const { return shade_ms_; }

 private:
  const SceneSpec& scene_;
  ProbeRelighting relighting_;
  ProbeLookup lookup_;
  Mesh scene_mesh_, moving_, display_;
  // What depends only on where points are, kept while the light turns: the
  // scene's lobes and weights once, the object's lobes once (a move keeps its
  // normals) and its weights after each move.
  Eigen::MatrixXd scene_lobes_, moving_lobes_;
  ProbeWeights scene_weights_, moving_weights_;
  Eigen::Vector3f position_ = Eigen::Vector3f::Zero();
  bool has_moving_ = false, moved_ = true;
  double incident_ms_ = 0, shade_ms_ = 0;
};

}  // namespace prt::view
