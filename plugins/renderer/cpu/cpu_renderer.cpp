// The reference renderer: per-vertex relighting on the CPU (per-cluster
// constants, then weighted sums) and a software rasteriser.
#include <array>

#include "prt/environment.hpp"
#include "prt/plugin.hpp"
#include "prt/renderer.hpp"
#include "prt/texel_render.hpp"
#include "rasterizer.hpp"

namespace prt {

class CpuRenderer final : public Renderer {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "software rasteriser with z-buffer and Gouraud shading; the reference for tests";
  static constexpr auto kBackground =
      param::boolean("background", "true", "draw the environment behind the mesh");
  static constexpr auto parameters() { return param::records(kBackground); }

  explicit CpuRenderer(const Params& params) : background_(kBackground(params)) {}

  Image render(const RenderInput& in) override {
    if (!in.mesh) throw Error("cpu renderer: no mesh");
    const Camera& camera = in.camera;
    Image image(camera.width, camera.height);
    if (background_ && in.background) draw_environment(*in.background, camera, image);
    if (in.texels) return draw_texels(in, image);
    const Eigen::MatrixX3f radiance = input_radiance(in, "cpu");
    if (radiance.rows() != static_cast<Eigen::Index>(in.mesh->vertex_count()))
      throw Error("cpu renderer: radiance rows do not match the mesh's vertices");
    rasterize(*in.mesh, radiance, camera, image);
    return image;
  }

 private:
  // Per-texel transfer: each pixel looks the radiance texture up at its uv
  // (perspective-correct), bilinearly.
  static Image draw_texels(const RenderInput& in, Image& image) {
    const RadianceTexture texture = texel_texture(in, "cpu");
    const Mesh& mesh = *in.mesh;
    MatrixXfRow uvs(Eigen::Index(mesh.vertex_count()), 2);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) uvs.row(Eigen::Index(v)) = mesh.uvs[v];
    rasterize(mesh, uvs, in.camera, image, [&](const float* uv, float* rgb) {
      const Eigen::Vector3f radiance = texture.lookup({uv[0], uv[1]});
      for (int c = 0; c < 3; ++c) rgb[c] = radiance[c];
    });
    return image;
  }

  bool background_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::CpuRenderer, "cpu")
