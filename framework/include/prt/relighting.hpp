// Viewing a bake: Relighting (the one relight path of render, bench,
// compare-bases, the viewer and Python) and the render of one image.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/environment.hpp"
#include "prt/frame.hpp"
#include "prt/image.hpp"
#include "prt/point_lights.hpp"
#include "prt/registry.hpp"
#include "prt/relight.hpp"
#include "prt/renderer.hpp"
#include "prt/run_options.hpp"
#include "prt/scene.hpp"
#include "prt/view_transfer.hpp"

namespace prt {

// For glossy transfer: a warning when the light vector's top frequency band
// holds more than 60% of band 0's energy (the light basis cannot hold
// the light: it rings, and the glossy lobe shows the rings); empty otherwise
// or for bases without bands.
std::string under_resolved_light(const Eigen::MatrixX3d& light, const std::vector<int>& bands);

struct Rendered {
  Image image;
  Eigen::MatrixX3f vertex_radiance;          // v x 3 including albedo (texels: one row per texel)
  std::map<std::string, double> statistics;  // the renderer's (overdraw, draw time, ...)
};

// One relighting of a bake's transfer (its compressed form or another encoding
// of it) for a light vector and camera: the exit basis's values toward the
// camera (glossy) and the radiance each vertex sends to it (albedo included).
struct Relit {
  MatrixXfRow exit_values;           // glossy only: v x N_r
  Eigen::MatrixX3f vertex_radiance;  // one row per transfer row (vertex or texel)
  // Point lights or per-channel transfers: the sums are made here, and
  // renderers draw vertex_radiance.
  bool summed = false;
};

// What viewing a bake needs, made once: its light basis (fitted state loaded)
// and, for glossy transfer, its exit basis and the vertices' frames. The one
// relight path of render, bench, compare-bases and the viewer.
class Relighting {
 public:
  // Checks the bake against the scene and its plug-ins.
  Relighting(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry);
  const Basis& basis() const { return *basis_; }
  // The light vector of an environment in the light basis ([lighting] window applied).
  Eigen::MatrixX3d light(const Environment& environment) const;
  // Throws unless `transfer` encodes this bake's transfer (vertices,
  // coefficients, indices) and `light` has one finite row per light-basis
  // coefficient: for inputs made elsewhere than the bake (the Python module).
  void check_inputs(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light) const;
  // Lays a transfer out for relighting frame after frame (viewer, bench).
  RelightKernel prepare(const CompressedTransfer& transfer) const;
  Relit relight(const RelightKernel& kernel, const Eigen::MatrixX3d& light,
                const Camera& camera) const;
  // Whether relight() makes the per-vertex sums itself (point lights or
  // per-channel transfers: Relit::summed) rather than leaving them to the
  // renderer's constants-and-weights path.
  // Per-texel transfer is summed here too: renderers look its sums up as a texture.
  bool sums_here() const {
    return data_.transfer.channel_groups > 1 || !point_lights_.empty() || data_.receivers.texels();
  }
  Relit relight(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                const Camera& camera) const {
    return relight(prepare(transfer), light, camera);
  }
  // For frames that change only the light: glossy `transfer` folded toward
  // `camera` (ViewTransfer: n_L x 3 multiply-adds a vertex a frame instead
  // of (n'_k + 1) N_r x 3). Empty where relight() makes other sums (diffuse
  // or per-channel transfer, point lights): use relight() there.
  std::optional<ViewTransfer> view(const CompressedTransfer& transfer, const Camera& camera) const;
  // Radiance toward the view's camera (albedo included): relight()'s
  // vertex_radiance for the view's transfer and camera, to float rounding.
  Eigen::MatrixX3f relight(const ViewTransfer& view, const Eigen::MatrixX3d& light) const;
  // Glossy: the exit basis toward the camera at each vertex (v x N_r); empty
  // for diffuse transfer.
  MatrixXfRow exit_values_toward(const Camera& camera) const;
  // The scene's point lights ([[lighting.point]]), which relight() adds.
  const std::vector<PointLight>& point_lights() const { return point_lights_; }
  void set_point_lights(std::vector<PointLight> lights);
  // From now on, point lights by brute-force re-projection of their caps
  // (`cap_samples` directions per vertex): the reference of the rule.
  void use_brute_force(int cap_samples);
  // How the light basis receives them (one line for logs); empty without lights.
  std::string point_light_rule() const;
  // What the point lights add (v x 3, albedo included); zero without lights.
  Eigen::MatrixX3f point_radiance(const CompressedTransfer& transfer,
                                  const MatrixXfRow* exit_values) const;
  // The renderer's input; points into the bake, `transfer` and `relit`.
  RenderInput input(const CompressedTransfer& transfer, const Relit& relit,
                    const Eigen::MatrixX3d& light, const Camera& camera) const;

 private:
  const SceneSpec& scene_;
  const BakeData& data_;
  // The light as the transfer's dot products need it: G l for a light basis
  // that is not orthonormal (t . G l = int T L), l itself otherwise.
  Eigen::MatrixX3d seen_by_transfer(const Eigen::MatrixX3d& light) const;

  std::shared_ptr<Basis> basis_, exit_;
  Eigen::MatrixXd light_gram_;  // empty for an orthonormal light basis
  std::vector<Frame> frames_;
  std::vector<PointLight> point_lights_;
  std::unique_ptr<PointLightProjector> projector_;
};

// One image: `transfer` (the bake's compressed form or another encoding of
// it) relit under `light` toward `camera` and drawn by `renderer`, over
// `background` when given. render() and the Python module use it.
Rendered render_relit(const Relighting& relighting, Renderer& renderer,
                      const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                      const Camera& camera, const Environment* background,
                      StageTimes* times = nullptr);

// Light projection -> per-cluster constants -> per-vertex sums -> image.
Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times, const RunOptions& options = {});

}  // namespace prt
