// The renderer interface: compressed transfer + light vector + camera -> image.
#pragma once
#include <Eigen/Core>
#include <map>
#include <string>

#include "prt/camera.hpp"
#include "prt/image.hpp"
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/texel_atlas.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Environment;  // prt/environment.hpp: a renderer that draws the background includes it

struct RenderInput {
  const Mesh* mesh = nullptr;
  // Either a compressed transfer with its light vector (n x 3)...
  const CompressedTransfer* transfer = nullptr;
  Eigen::MatrixX3d light;
  // ...or exit radiance given directly per vertex (v x 3), e.g. ground truth.
  const Eigen::MatrixX3f* vertex_radiance = nullptr;
  // Glossy transfer: the exit basis evaluated toward the camera at each
  // vertex (v x N_r, in the vertex's local frame). A vertex's stored vector
  // is then an N_r x N_i matrix; its radiance is exit_values_p . (M_p l).
  // Evaluating per vertex keeps every local-frame quantity at its vertex:
  // nothing expressed in one vertex's frame is interpolated into another's.
  const MatrixXfRow* exit_values = nullptr;
  Eigen::Vector3f albedo{1, 1, 1};
  Camera camera;
  const Environment* background = nullptr;  // drawn behind the mesh when set
  // Per-texel transfer: the radiance (vertex_radiance, or the transfer's
  // sums) has one row per texel of this atlas, looked up through the mesh's
  // uvs (radiance_texture in prt/texel_atlas.hpp) instead of interpolated
  // from vertices.
  const TexelAtlas* texels = nullptr;
};

class Renderer : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::renderer;
  virtual Image render(const RenderInput& input) = 0;
  // Figures of the last render, e.g. relight_seconds (per-cluster constants),
  // draw_seconds, overdraw (triangles drawn / triangles in the mesh).
  virtual std::map<std::string, double> statistics() const { return {}; }
  // Capability: draws with OpenGL on the GPU. prt-view and `prt bench --gpu`
  // use such a renderer (the scene's when it is one, else the first
  // registered: gpu_renderer in prt/registry.hpp), never one by name.
  virtual bool draws_on_gpu() const { return false; }
};

}  // namespace prt
