#include "probe_view.hpp"

#include "prt/mesh_compose.hpp"
#include "prt/probe_transfer.hpp"
#include "prt/progress.hpp"

namespace prt::view {

ProbeView::ProbeView(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry)
    : scene_(scene), relighting_(scene, data, registry), scene_mesh_(data.mesh) {
  lookup_ = relighting_.lookup();
  scene_lobes_ = relighting_.lobes(scene_mesh_);
  scene_weights_ = relighting_.weights(scene_mesh_, lookup_);
  has_moving_ = scene.has_moving();
  if (has_moving_) {
    position_ = Eigen::Vector3d(keys::place::position(scene.moving).data()).cast<float>();
    moving_ = scene.load_moving(position_);
    moving_lobes_ = relighting_.lobes(moving_);
  }
}

void ProbeView::move(const Eigen::Vector3f& offset) {
  if (!has_moving_) return;
  for (Eigen::Vector3f& p : moving_.positions) p += offset;
  position_ += offset;
  moved_ = true;
}

const Mesh& ProbeView::display() {
  if (moved_) {
    display_ = scene_mesh_;
    if (has_moving_) {
      append(display_, moving_);
      moving_weights_ = relighting_.weights(moving_, lookup_);
    }
    moved_ = false;
  }
  return display_;
}

Eigen::MatrixX3f ProbeView::radiance(const CompressedTransfer& transfer,
                                     const Eigen::MatrixX3d& light) {
  const Mesh& shown = display();
  Stopwatch clock;
  const std::vector<Eigen::MatrixX3d> incident = relighting_.incident(transfer, light);
  incident_ms_ = 1000 * clock.seconds();
  clock = Stopwatch();
  Eigen::MatrixX3f out(Eigen::Index(shown.vertex_count()), 3);
  const auto scene_rows = Eigen::Index(scene_mesh_.vertex_count());
  out.topRows(scene_rows) = shade_with(scene_weights_, scene_lobes_, incident);
  if (has_moving_)
    out.bottomRows(out.rows() - scene_rows) = shade_with(moving_weights_, moving_lobes_, incident);
  const Eigen::Vector3f albedo = scene_.albedo();
  for (int c = 0; c < 3; ++c) out.col(c) *= albedo[c];
  shade_ms_ = 1000 * clock.seconds();
  return out;
}

}  // namespace prt::view
