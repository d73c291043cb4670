// The renderer interface: compressed transfer + light vector + camera -> image.
#pragma once
#include <Eigen/Core>
#include <map>
#include <string>

#include "prt/camera.hpp"
#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/image.hpp"
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/transfer.hpp"

namespace prt {

struct RenderInput {
  const Mesh* mesh = nullptr;
  // Either a compressed transfer with its light vector (n x 3)...
  const CompressedTransfer* transfer = nullptr;
  Eigen::MatrixX3d light;
  // ...or exit radiance given directly per vertex (v x 3), e.g. ground truth.
  const Eigen::MatrixX3f* vertex_radiance = nullptr;
  // Glossy transfer (when exit_basis is set): the exit basis, the vertices'
  // local frames and optionally the exit coefficients per vertex (v x 3 N_r,
  // as exit_coefficients returns; renderers that compute them from transfer
  // and light ignore them). The renderer evaluates y(v_p) . e_p per pixel
  // with the local view vector.
  const MatrixXfRow* exit_coefficients = nullptr;
  const ExitBasis* exit_basis = nullptr;
  const std::vector<Frame>* frames = nullptr;
  Eigen::Vector3f albedo{1, 1, 1};
  Camera camera;
  const Environment* background = nullptr;  // drawn behind the mesh when set
};

class Renderer : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::renderer;
  virtual Image render(const RenderInput& input) = 0;
  // Figures of the last render, e.g. relight_seconds (per-cluster constants),
  // draw_seconds, overdraw (triangles drawn / triangles in the mesh).
  virtual std::map<std::string, double> statistics() const { return {}; }
};

}  // namespace prt
