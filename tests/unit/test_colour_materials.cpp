// Colour materials: per-channel diffuse, specular and subsurface
// coefficients; a transfer per distinct channel only where the channels'
// transfers differ, each channel equal to a grey bake of its own material.
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "prt/bake_file.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"

using namespace prt;

namespace {

SceneSpec scene(PluginRegistry& registry, const std::string& material,
                const std::string& extra = "") {
  const std::string text = R"(
[mesh]
generate = "open-box"
detail = 1
[material]
)" + material + R"(
[transport]
rays = 256
)" + extra + R"(
[basis]
plugin = "sh"
order = 4
[exit]
plugin = "hsh"
order = 3
[lighting]
constant = [1.0, 0.7, 0.4]
[camera]
position = [0.4, 3.0, 1.5]
[ground_truth]
samples = 64
)";
  return SceneSpec::parse(text, "colour.toml", registry);
}

Eigen::MatrixX3f relit(const SceneSpec& s, const BakeData& data, PluginRegistry& registry) {
  const Relighting relighting(s, data, registry);
  return relighting
      .relight(data.compressed, relighting.light(s.load_environment()), s.make_camera(data.mesh))
      .vertex_radiance;
}

double column_difference(const Eigen::MatrixX3f& a, int ca, const Eigen::MatrixX3f& b, int cb) {
  return (a.col(ca) - b.col(cb)).norm() / std::max(1e-12f, b.col(cb).norm());
}

}  // namespace

TEST_CASE("a coloured glossy material bakes one transfer per distinct channel", "[colour]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const SceneSpec colour =
      scene(registry, "brdf = \"phong\"\ndiffuse = [0.8, 0.3, 0.3]\nspecular = 0.5\nexponent = 8");
  const MaterialChannels channels = colour.channels();
  REQUIRE(channels.groups.size() == 2);  // green and blue agree
  CHECK(channels.group_of_channel == std::array<int, 3>{0, 1, 1});
  StageTimes times;
  const BakeData data = bake(colour, registry, {true}, times);
  CHECK(data.transfer.channel_groups == 2);
  const Eigen::MatrixX3f radiance = relit(colour, data, registry);
  // Each channel is the grey bake of its own kd.
  for (const auto& [kd, channel] : {std::pair{"0.8", 0}, {"0.3", 1}, {"0.3", 2}}) {
    const SceneSpec grey = scene(registry, std::string("brdf = \"phong\"\ndiffuse = ") + kd +
                                               "\nspecular = 0.5\nexponent = 8");
    REQUIRE(grey.channels().groups.size() == 1);
    const BakeData grey_data = bake(grey, registry, {true}, times);
    INFO("channel " << channel);
    CHECK(column_difference(radiance, channel, relit(grey, grey_data, registry), channel) < 1e-5);
    // The ground truth too: one Monte Carlo run per channel material.
    const Camera camera = colour.make_camera(data.mesh);
    const Eigen::MatrixX3f truth =
        ground_truth_vertices(colour, data.mesh, colour.load_environment(), camera, {true});
    const Eigen::MatrixX3f grey_truth =
        ground_truth_vertices(grey, data.mesh, grey.load_environment(), camera, {true});
    CHECK(column_difference(truth, channel, grey_truth, channel) < 1e-6);
  }
  // The channels survive the bake file.
  const auto file = std::filesystem::temp_directory_path() / "prt_colour_test.h5";
  write_bake(file, data);
  const BakeData read = read_bake(file);
  std::filesystem::remove(file);
  CHECK(read.transfer.channel_groups == 2);
  CHECK(read.transfer.group_of_channel == channels.group_of_channel);
  CHECK(column_difference(relit(colour, read, registry), 0, radiance, 0) < 1e-6);
}

TEST_CASE("channels share one transfer unless they must differ", "[colour]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  // Lambert without bounces: kd is a tint, one transfer.
  CHECK(scene(registry, "diffuse = [0.9, 0.5, 0.2]").channels().groups.size() == 1);
  CHECK(scene(registry, "diffuse = [0.9, 0.5, 0.2]")
            .albedo()
            .isApprox(Eigen::Vector3f(0.72f, 0.4f, 0.16f)));  // x the default albedo 0.8
  // With bounces the colour changes the light between bounces: three transfers.
  CHECK(scene(registry, "diffuse = [0.9, 0.5, 0.2]", "bounces = 1").channels().groups.size() == 3);
  // Grey glossy: one.
  CHECK(scene(registry, "brdf = \"ward\"\nspecular = [0.4, 0.4, 0.4]").channels().groups.size() ==
        1);
  // Measured subsurface coefficients differ in every channel.
  const SceneSpec marble = scene(registry, "subsurface = true\npreset = \"marble\"");
  CHECK(marble.channels().groups.size() == 3);
  CHECK(marble.subsurface(1).sigma_s == Approx(2.62));
  CHECK(marble.subsurface(2).sigma_a == Approx(0.0071));
  CHECK(marble.subsurface(0).eta == Approx(1.3));
  CHECK_THROWS_WITH(scene(registry, "subsurface = true\npreset = \"marble\"\nsigma_a = 0.1"),
                    Catch::Contains("preset or sigma_a, not both"));
  CHECK_THROWS_WITH(scene(registry, "preset = \"marbel\""), Catch::Contains("did you mean"));
}

TEST_CASE("ketchup glows red: per-channel subsurface transfers", "[colour][subsurface]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  SceneSpec ketchup =
      scene(registry,
            "albedo = 1\nbrdf = \"phong\"\ndiffuse = 0\nspecular = 0\nsubsurface = true\n"
            "preset = \"ketchup\"\n"
            "mm_per_unit = 20");
  StageTimes times;
  const BakeData data = bake(ketchup, registry, {true}, times);
  CHECK(data.transfer.channel_groups == 3);
  const Eigen::MatrixX3f radiance = relit(ketchup, data, registry);
  // Under light [1, 0.7, 0.4] red scatters farthest and absorbs least.
  CHECK(radiance.col(0).mean() > 3 * radiance.col(1).mean());
  CHECK(radiance.col(1).mean() > radiance.col(2).mean());
  const Eigen::MatrixX3f truth = ground_truth_vertices(
      ketchup, data.mesh, ketchup.load_environment(), ketchup.make_camera(data.mesh), {true});
  const ErrorStats e = vertex_error(radiance, truth);
  INFO("relative RMS " << e.relative_rms);
  CHECK(e.relative_rms < 0.1);
}

TEST_CASE("point lights refuse per-channel transfers with a clear message", "[colour]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const std::string material = "brdf = \"phong\"\ndiffuse = [0.8, 0.3, 0.3]";
  const SceneSpec s = scene(registry, material);
  StageTimes times;
  const BakeData data = bake(s, registry, {true}, times);
  SceneSpec lit = s;
  PointLight light;
  light.position = Eigen::Vector3d(0, 3, 0);
  lit.point_lights.push_back(light);
  CHECK_THROWS_WITH(Relighting(lit, data, registry),
                    Catch::Contains("colour.toml") && Catch::Contains("grey coefficients"));
}
