// Glossy inter-reflection: the bounces converge, add no energy in a white
// furnace, vanish on a convex object, and bring an open box's transfer
// closer to the path-traced ground truth with the same bounces.
#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

#include "prt/environment.hpp"
#include "prt/frame.hpp"
#include "prt/ground_truth.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"

using namespace prt;

namespace {

const char* kScene = R"(
[mesh]
generate = "%s"
detail = 3
[material]
albedo = [1, 1, 1]
brdf = "phong"
diffuse = 0.5
specular = 0.5
exponent = 6
[transport]
rays = 512
bounces = %d
[basis]
plugin = "sh"
order = 5
[exit]
plugin = "hsh"
order = 4
[lighting]
constant = [1, 1, 1]
[camera]
position = [1.2, 2.0, 2.6]
[ground_truth]
samples = 400
)";

SceneSpec scene(PluginRegistry& registry, const char* mesh, int bounces,
                const std::string& brdf = "phong", double kd = 0.5) {
  char text[1024];
  std::snprintf(text, sizeof text, kScene, mesh, bounces);
  std::string t = text;
  t.replace(t.find("brdf = \"phong\""), 14, "brdf = \"" + brdf + "\"");
  if (kd != 0.5) {
    t.replace(t.find("diffuse = 0.5"), 13, "diffuse = " + std::to_string(kd));
    t.replace(t.find("specular = 0.5"), 14, "specular = 0.0");
  }
  return SceneSpec::parse(t, "glossy_bounces.toml", registry);
}

struct Baked {
  BakeData data;
  Eigen::MatrixX3f total, direct;  // relit toward the scene's camera
};

Baked bake_and_relight(const SceneSpec& s, PluginRegistry& registry) {
  StageTimes times;
  Baked out{bake(s, registry, {true}, times), {}, {}};
  const Relighting relighting(s, out.data, registry);
  const Eigen::MatrixX3d light = relighting.light(s.load_environment());
  const Camera camera = s.make_camera(out.data.mesh);
  out.total = relighting.relight(exact_form(out.data.transfer), light, camera).vertex_radiance;
  if (out.data.direct.coefficients.size())
    out.direct = relighting.relight(exact_form(out.data.direct), light, camera).vertex_radiance;
  return out;
}

}  // namespace

TEST_CASE("glossy bounces converge and add no energy in a white furnace", "[glossy][bounces]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const Baked box = bake_and_relight(scene(registry, "open-box", 3), registry);
  const auto& m = box.data.metrics;
  REQUIRE(m.count("bounce_3_norm"));
  CHECK(m.at("bounce_1_norm") > 0);
  CHECK(m.at("bounce_2_norm") < m.at("bounce_1_norm"));  // each bounce adds less
  CHECK(m.at("bounce_3_norm") < m.at("bounce_2_norm"));
  REQUIRE(box.direct.rows() == box.total.rows());
  CHECK(box.total.allFinite());
  // kd + ks = 1 under light 1: the box never sends more than 1 (band-limited
  // lobes ring a little), and the bounces only add light.
  CHECK(box.total.maxCoeff() < 1.05f);
  CHECK((box.total - box.direct).minCoeff() > -0.02f);
  CHECK((box.total - box.direct).mean() > 0.02f);
}

TEST_CASE("glossy bounces add nothing on a convex sphere", "[glossy][bounces]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const Baked sphere = bake_and_relight(scene(registry, "sphere", 2), registry);
  CHECK(sphere.data.metrics.at("bounce_1_norm") == 0);
  CHECK((sphere.total - sphere.direct).cwiseAbs().maxCoeff() == 0);
  // The path-traced ground truth's bounces vanish there too.
  const SceneSpec s = scene(registry, "sphere", 2);
  const Mesh mesh = s.load_mesh();
  const Eigen::MatrixXd views =
      local_view_directions(mesh, tangent_frames(mesh), s.make_camera(mesh).position);
  const Eigen::MatrixX3f bounces = ground_truth_glossy_bounces(mesh, s.load_environment(), s.brdf(),
                                                               views, 2, 1.0, 64, 1, nullptr);
  CHECK(bounces.cwiseAbs().maxCoeff() == 0);
}

TEST_CASE("an open box's glossy bounces match the ground truth's better than no bounces",
          "[glossy][bounces]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const SceneSpec s = scene(registry, "open-box", 2);
  const Baked box = bake_and_relight(s, registry);
  const Eigen::MatrixX3f truth = ground_truth_vertices(s, box.data.mesh, s.load_environment(),
                                                       s.make_camera(box.data.mesh), {true});
  const ErrorStats with = vertex_error(box.total, truth);
  const ErrorStats without = vertex_error(box.direct, truth);
  INFO("relative RMS with bounces " << with.relative_rms << ", without " << without.relative_rms);
  CHECK(with.relative_rms < 0.5 * without.relative_rms);
  // Per-vertex transfer interpolates over triangles, the paths do not: at
  // detail 3 that costs about 5% of the bounced light.
  CHECK(with.relative_rms < 0.3 * without.relative_rms);
  CHECK(with.relative_rms < 0.15);
  // The ground truth's furnace: never above the light.
  CHECK(truth.maxCoeff() < 1.05f);
}

TEST_CASE("a Lambertian lobe through the glossy bounces equals diffuse inter-reflection",
          "[glossy][bounces]") {
  // With kd = 1, ks = 0 the glossy path is exact for cosine-weighted light
  // (z lies in the span of hemispherical SH), so its bounces must reproduce
  // the diffuse path's, which shares no code with them.
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const Baked glossy = bake_and_relight(scene(registry, "open-box", 2, "phong", 1.0), registry);
  const Baked diffuse = bake_and_relight(scene(registry, "open-box", 2, "lambert", 1.0), registry);
  REQUIRE(glossy.data.transfer.glossy());
  REQUIRE_FALSE(diffuse.data.transfer.glossy());
  const ErrorStats e = vertex_error(glossy.total, diffuse.total);
  INFO("max difference " << e.max << ", mean radiance " << diffuse.total.mean());
  CHECK(e.max < 2e-3);
  CHECK((glossy.total - glossy.direct).mean() > 0.1f);
}

TEST_CASE("a view relights glossy transfer as relight() does, while the camera stays",
          "[glossy][view]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const SceneSpec s = scene(registry, "sphere", 0);
  StageTimes times;
  const BakeData data = bake(s, registry, {true}, times);
  Relighting relighting(s, data, registry);
  const Camera camera = s.make_camera(data.mesh);
  const std::optional<ViewTransfer> view = relighting.view(data.compressed, camera);
  REQUIRE(view);
  for (int trial = 0; trial < 3; ++trial) {  // three lights, one view
    const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(relighting.basis().size(), 3);
    const Eigen::MatrixX3f expected =
        relighting.relight(data.compressed, light, camera).vertex_radiance;
    const Eigen::MatrixX3f viewed = relighting.relight(*view, light);
    CHECK((viewed - expected).cwiseAbs().maxCoeff() <= 1e-5f * expected.cwiseAbs().maxCoeff());
  }
  // Point lights are summed by relight(transfer, light, camera) only.
  relighting.set_point_lights({PointLight{}});
  CHECK_FALSE(relighting.view(data.compressed, camera));
  CHECK_THROWS_WITH(relighting.relight(*view, relighting.light(s.load_environment())),
                    Catch::Contains("point lights"));
}
