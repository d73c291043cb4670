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
    if (background_ && in.background) draw_environment(*in.background, camera, image);
    if (in.exit_basis && !in.vertex_radiance) {
      draw_glossy(in, image);
      return image;
    }
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
  // Sloan 2003 §6: e_p and the local view vector v_p are interpolated over
  // each triangle; each pixel evaluates y(v_p) . e_p.
  static void draw_glossy(const RenderInput& in, Image& image) {
    const Mesh& mesh = *in.mesh;
    if (!in.exit_basis || !in.frames) throw Error("cpu renderer: glossy input lacks its basis");
    const ExitBasis& exit = *in.exit_basis;
    const int rows = exit.rows();
    if (!in.exit_coefficients && !in.transfer) throw Error("cpu renderer: no glossy transfer");
    const MatrixXfRow e = in.exit_coefficients ? *in.exit_coefficients
                                               : exit_coefficients(*in.transfer, in.light, rows);
    if (e.rows() != Eigen::Index(mesh.vertex_count()) || e.cols() != 3 * rows ||
        in.frames->size() != mesh.vertex_count())
      throw Error("cpu renderer: glossy input does not match the mesh");
    MatrixXfRow attributes(e.rows(), 3 * rows + 3);
    attributes.leftCols(3 * rows) = e;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      attributes.row(Eigen::Index(v)).tail<3>() =
          ((*in.frames)[v] * (in.camera.position - mesh.positions[v]).cast<double>().normalized())
              .cast<float>()
              .transpose();
    const Eigen::Vector3f albedo = in.albedo;
    rasterize(mesh, attributes, in.camera, image, [&](const float* a, float* rgb) {
      double y[kMaxExitCoefficients];
      exit.evaluate(
          upper_hemisphere(Eigen::Vector3d(a[3 * rows], a[3 * rows + 1], a[3 * rows + 2])), y);
      for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int i = 0; i < rows; ++i) sum += y[i] * a[3 * i + c];
        rgb[c] = std::max(0.f, albedo[c] * static_cast<float>(sum));
      }
    });
  }

  bool background_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::CpuRenderer, "cpu")
