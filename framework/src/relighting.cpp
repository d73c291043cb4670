// Relighting: the one relight path (light projection, per-cluster constants,
// per-vertex sums, exit basis toward the camera, point lights).
#include "prt/relighting.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "prt/bake_checks.hpp"
#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/renderer.hpp"

namespace prt {

Relighting::Relighting(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry)
    : scene_(scene), data_(data) {
  if (data.receivers.probes())  // rows are probes, not vertices: ProbeRelighting views them
    throw Error(scene.receivers.location(),
                "this bake holds transfer at probes, which prt render and prt probes view "
                "(docs/receivers.md); this view draws transfer at vertices");
  check_bake_matches(data, scene);
  PluginChoice basis = scene.basis;
  basis_ = registry.create<Basis>(basis.name, basis.params, basis.where);
  basis_->load(data.basis_state);
  check_bake_dimension(data, *basis_);
  scene.check_window(*basis_);
  if (BasisMetric metric = basis_metric(*basis_); !metric.identity)
    light_gram_ = std::move(metric.gram);
  if (data.transfer.glossy()) {
    PluginChoice exit = scene.exit;
    exit_ = registry.create<Basis>(exit.name, exit.params, exit.where);
    exit_->load(data.exit_state);
    if (exit_->size() != data.transfer.exit_rows)
      throw Error(exit.where, "the bake's transfer has " + std::to_string(data.transfer.exit_rows) +
                                  " exit rows, but exit basis \"" + exit.name + "\" has " +
                                  std::to_string(exit_->size()) + " functions; bake again");
    frames_ = tangent_frames(data.row_mesh());
  }
  if (!scene.point_lights.empty() && data.transfer.channel_groups > 1)
    throw Error(scene.material.location(),
                "point lights need one transfer for all colour channels; this material's "
                "channels differ (coloured diffuse/specular with glossy or bounces, or coloured "
                "subsurface): use grey coefficients with point lights");
  set_point_lights(scene.point_lights);
}

void Relighting::set_point_lights(std::vector<PointLight> lights) {
  point_lights_ = std::move(lights);
  if (!point_lights_.empty() && !projector_)
    projector_ = std::make_unique<PointLightProjector>(
        *basis_, static_cast<int>(keys::lighting::nearest(scene_.lighting)));
}

void Relighting::use_brute_force(int cap_samples) {
  projector_ =
      std::make_unique<PointLightProjector>(PointLightProjector::brute_force(*basis_, cap_samples));
}

std::string Relighting::point_light_rule() const {
  return point_lights_.empty() ? "" : projector_->describe();
}

Eigen::MatrixX3f Relighting::point_radiance(const CompressedTransfer& transfer,
                                            const MatrixXfRow* exit_values) const {
  const auto v = static_cast<Eigen::Index>(data_.row_mesh().vertex_count());
  if (point_lights_.empty()) return Eigen::MatrixX3f::Zero(v, 3);
  Eigen::MatrixX3f radiance =
      point_light_radiance(data_.row_mesh(), transfer, data_.transfer.exit_rows, *projector_,
                           point_lights_, exit_ ? exit_values : nullptr);
  for (int c = 0; c < 3; ++c) radiance.col(c) *= data_.albedo[c];
  return radiance;
}

Eigen::MatrixX3d Relighting::light(const Environment& environment) const {
  return scene_.project_light(environment, *basis_);
}

Eigen::MatrixX3d Relighting::seen_by_transfer(const Eigen::MatrixX3d& light) const {
  if (light_gram_.size() == 0) return light;
  return light_gram_ * light;
}

RelightKernel Relighting::prepare(const CompressedTransfer& transfer) const {
  return RelightKernel(transfer, data_.transfer.exit_rows * data_.transfer.channel_groups);
}

namespace {

// Colour channels from stacked channel transfers: channel c of the exit
// coefficients of block group_of_channel[c], read toward the camera (glossy).
Eigen::MatrixX3f channel_radiance(const RelightKernel& kernel, const Eigen::MatrixX3d& light,
                                  const TransferSignal& layout, const MatrixXfRow* exit_values) {
  const MatrixXfRow e = kernel.exit_coefficients(light);  // v x 3 (G N_r), RGB interleaved
  const int n_r = layout.exit_rows;
  Eigen::MatrixX3f out(e.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), e.rows(), [&](Eigen::Index p) {
    for (int c = 0; c < 3; ++c) {
      const int first = layout.group_of_channel[std::size_t(c)] * n_r;
      float sum = 0;
      for (int r = 0; r < n_r; ++r)
        sum += (exit_values ? (*exit_values)(p, r) : 1.f) * e(p, 3 * (first + r) + c);
      out(p, c) = sum;
    }
  });
  return out;
}

}  // namespace

Relit Relighting::relight(const RelightKernel& kernel, const Eigen::MatrixX3d& light_coefficients,
                          const Camera& camera) const {
  const Eigen::MatrixX3d light = seen_by_transfer(light_coefficients);
  Relit out;
  out.exit_values = exit_values_toward(camera);  // empty for diffuse transfer
  // The renderers' own relight path (RelightKernel), so CPU results are theirs.
  const MatrixXfRow* exit_values = exit_ ? &out.exit_values : nullptr;
  if (data_.transfer.channel_groups > 1) {  // per-channel transfers: summed here (sums_here)
    out.vertex_radiance = channel_radiance(kernel, light, data_.transfer, exit_values);
    out.summed = true;
  } else {
    out.vertex_radiance = kernel.radiance(light, exit_values);
  }
  for (int c = 0; c < 3; ++c) out.vertex_radiance.col(c) *= data_.albedo[c];
  if (!point_lights_.empty()) {
    out.vertex_radiance += point_radiance(kernel.transfer(), &out.exit_values);
    out.summed = true;
  }
  if (data_.receivers.texels()) out.summed = true;  // renderers draw the texels' sums as a texture
  return out;
}

std::optional<ViewTransfer> Relighting::view(const CompressedTransfer& transfer,
                                             const Camera& camera) const {
  if (!exit_ || sums_here()) return std::nullopt;
  check_encoding(data_, transfer, "relight");
  return ViewTransfer(transfer, exit_values_toward(camera));
}

Eigen::MatrixX3f Relighting::relight(const ViewTransfer& view,
                                     const Eigen::MatrixX3d& light_coefficients) const {
  if (sums_here())
    throw Error("relight: a view's sums leave out point lights and per-channel transfers");
  view.check_light(light_coefficients);  // before the metric's product reads it
  Eigen::MatrixX3f radiance = view.radiance(seen_by_transfer(light_coefficients));
  for (int c = 0; c < 3; ++c) radiance.col(c) *= data_.albedo[c];
  return radiance;
}

MatrixXfRow Relighting::exit_values_toward(const Camera& camera) const {
  if (!exit_) return {};
  return exit_values(*exit_, local_view_directions(data_.row_mesh(), frames_, camera.position));
}

RenderInput Relighting::input(const CompressedTransfer& transfer, const Relit& relit,
                              const Eigen::MatrixX3d& light, const Camera& camera) const {
  RenderInput input;
  input.mesh = &data_.mesh;
  input.transfer = &transfer;
  input.light = seen_by_transfer(light);
  input.albedo = data_.albedo;
  input.camera = camera;
  if (exit_) input.exit_values = &relit.exit_values;
  if (relit.summed) {  // point lights, channel transfers or texels: the renderer draws these sums
    input.vertex_radiance = &relit.vertex_radiance;
    input.albedo = Eigen::Vector3f::Ones();
  }
  if (data_.receivers.texels()) input.texels = &data_.receivers.atlas;
  return input;
}

void Relighting::check_inputs(const CompressedTransfer& transfer,
                              const Eigen::MatrixX3d& light) const {
  check_encoding(data_, transfer, "relight");
  if (light.rows() != basis_->size() || !light.allFinite())
    throw Error("relight: the light must be a finite " + std::to_string(basis_->size()) +
                " x 3 array (one row per coefficient of the light basis), not " +
                std::to_string(light.rows()) + " x 3");
}

}  // namespace prt
