// The reference renderer: per-vertex relighting on the CPU (per-cluster
// constants, then weighted sums) and a software rasteriser.
#include <array>

#include "prt/plugin.hpp"
#include "prt/renderer.hpp"
#include "rasterizer.hpp"

namespace prt {

class CpuRenderer final : public Renderer {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "software rasteriser with z-buffer and Gouraud shading; the reference for tests";
  static constexpr auto parameters() {
    return std::array{
        schema::boolean("background", "true", "draw the environment behind the mesh")};
  }

  explicit CpuRenderer(const Params& params) : background_(params.get_bool("background")) {}

  Image render(const RenderInput& in) override {
    if (!in.mesh) throw Error("cpu renderer: no mesh");
    const Camera& camera = in.camera;
    Image image(camera.width, camera.height);
    if (background_ && in.background) draw_background(*in.background, camera, image);
    Eigen::MatrixX3f radiance;
    if (in.vertex_radiance)
      radiance = *in.vertex_radiance;
    else if (in.transfer)
      radiance = relight(*in.transfer, in.light);
    else
      throw Error("cpu renderer: neither transfer nor vertex radiance given");
    if (radiance.rows() != static_cast<Eigen::Index>(in.mesh->vertex_count()))
      throw Error("cpu renderer: radiance rows do not match the mesh's vertices");
    for (int c = 0; c < 3; ++c) radiance.col(c) *= in.albedo[c];
    radiance = radiance.cwiseMax(0.f);  // negative SH ringing is not light
    rasterize(*in.mesh, radiance, camera, image);
    return image;
  }

 private:
  static void draw_background(const Environment& env, const Camera& camera, Image& image) {
    const Eigen::Vector3f f = (camera.target - camera.position).normalized();
    const Eigen::Vector3f s = f.cross(camera.up).normalized();
    const Eigen::Vector3f u = s.cross(f);
    const float t = std::tan(0.5f * camera.fov_degrees * float(M_PI) / 180.f);
    const float aspect = float(camera.width) / float(camera.height);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const float sx = (2.f * (x + 0.5f) / image.width - 1.f) * t * aspect;
        const float sy = (1.f - 2.f * (y + 0.5f) / image.height) * t;
        const Eigen::Vector3f d = (f + sx * s + sy * u).normalized();
        const Eigen::Vector3f l = env.radiance(d.cast<double>());
        float* out = image.at(x, y);
        for (int c = 0; c < 3; ++c) out[c] = l[c];
      }
  }

  bool background_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::CpuRenderer, "cpu")
