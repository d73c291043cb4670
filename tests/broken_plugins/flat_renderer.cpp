// A renderer with the bugs the renderer kit must catch: it fills the whole
// frame with the mean vertex radiance (no coverage, no background, no depth
// order). PRT_TEST_SMALL_IMAGE also draws one column short.
#include "prt/plugin.hpp"
#include "prt/renderer.hpp"

namespace {

class FlatRenderer final : public prt::Renderer {
 public:
  static constexpr const char* plugin_version = "0.0.1";
  static constexpr const char* plugin_description = "broken on purpose: the renderer kit's test";
  static constexpr auto parameters() { return prt::param::records(); }
  explicit FlatRenderer(const prt::Params&) {}

  prt::Image render(const prt::RenderInput& in) override {
#ifdef PRT_TEST_SMALL_IMAGE
    prt::Image image(in.camera.width - 1, in.camera.height);
#else
    prt::Image image(in.camera.width, in.camera.height);
#endif
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    if (in.vertex_radiance && in.vertex_radiance->rows() > 0)
      mean = in.vertex_radiance->colwise().mean().transpose();
    for (std::size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = mean[int(i % 3)];
    return image;
  }
};

}  // namespace

PRT_EXPORT_PLUGIN(FlatRenderer, "flat")
