// The render path: a bake relit under the scene's light and drawn by its renderer.
#include <algorithm>
#include <cstdio>

#include "prt/environment.hpp"
#include "prt/probe_render.hpp"
#include "prt/progress.hpp"
#include "prt/relighting.hpp"
#include "prt/renderer.hpp"

namespace prt {

std::string under_resolved_light(const Eigen::MatrixX3d& light, const std::vector<int>& bands) {
  if (bands.size() != static_cast<std::size_t>(light.rows()) || bands.empty()) return "";
  const int top = *std::max_element(bands.begin(), bands.end());
  if (top == 0) return "";
  double band0 = 0, band_top = 0;
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const double energy = light.row(Eigen::Index(i)).squaredNorm();
    if (bands[i] == 0) band0 += energy;
    if (bands[i] == top) band_top += energy;
  }
  if (!(band_top > 0.6 * band0)) return "";
  char text[400];
  std::snprintf(text, sizeof text,
                "the light's top band (l = %d) holds %.0f%% of band 0's energy: the light basis "
                "is too small for this light, which rings, and a glossy lobe shows the rings as "
                "dark seams and blotches; raise [basis] order",
                top, 100 * band_top / std::max(band0, 1e-300));
  return text;
}

Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times, const RunOptions& options) {
  if (data.receivers.probes()) return render_probes(scene, data, registry, times, options);
  Stopwatch clock;
  const Relighting relighting(scene, data, registry);
  PluginChoice renderer_choice = scene.renderer;
  auto renderer = registry.create<Renderer>(renderer_choice.name, renderer_choice.params,
                                            renderer_choice.where);
  const Environment environment = scene.load_environment();
  times.add("load lighting + plug-ins", clock.seconds());

  clock = Stopwatch();
  const Eigen::MatrixX3d light = relighting.light(environment);
  const Camera camera = scene.make_camera(data.mesh);
  times.add("project light", clock.seconds());
  if (data.transfer.glossy())
    if (const std::string warning =
            under_resolved_light(light, relighting.basis().coefficient_bands());
        !warning.empty())
      options.warn(warning);

  if (!scene.point_lights.empty())
    options.message("point lights (" + std::to_string(scene.point_lights.size()) +
                    "): " + relighting.point_light_rule());
  Rendered out =
      render_relit(relighting, *renderer, data.compressed, light, camera, &environment, &times);
  return out;
}

Rendered render_relit(const Relighting& relighting, Renderer& renderer,
                      const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                      const Camera& camera, const Environment* background, StageTimes* times) {
  Stopwatch clock;
  Rendered out;
  const Relit relit = relighting.relight(transfer, light, camera);
  out.vertex_radiance = relit.vertex_radiance;
  if (times) times->add("relight vertices", clock.seconds());
  clock = Stopwatch();
  RenderInput input = relighting.input(transfer, relit, light, camera);
  input.background = background;
  out.image = renderer.render(input);
  out.statistics = renderer.statistics();
  if (times) times->add("rasterise", clock.seconds());
  return out;
}

}  // namespace prt
