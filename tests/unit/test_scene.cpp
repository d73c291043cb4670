#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "prt/compressor.hpp"
#include "prt/mesh.hpp"
#include "prt/registry.hpp"
#include "prt/renderer.hpp"
#include "prt/scene.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {
const PluginRegistry& registry() {
  static const PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  return r;
}

SceneSpec parse(const std::string& text) {
  return SceneSpec::parse(text, fs::temp_directory_path() / "scene.toml", registry());
}

const std::string kValid = R"([mesh]
generate = "sphere"
[lighting]
constant = [1, 1, 1]
[basis]
plugin = "sh"
order = 4
)";
}  // namespace

TEST_CASE("a valid scene fills defaults for every section", "[scene]") {
  const SceneSpec s = parse(kValid);
  CHECK(s.basis.params.get_int("order") == 4);
  // The defaults by what they can do: an exact compressor, a renderer that
  // needs no display (it draws a bare mesh without any OpenGL context).
  PluginRegistry plugins({PRT_BUILD_PLUGIN_DIR});
  Params compressor = s.compressor.params, renderer = s.renderer.params;
  CHECK(plugins.create<Compressor>(s.compressor.name, compressor)->exact());
  Mesh triangle;
  triangle.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  triangle.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  triangle.triangles = {{0, 1, 2}};
  const Eigen::MatrixX3f radiance = Eigen::MatrixX3f::Ones(3, 3);
  RenderInput input;
  input.mesh = &triangle;
  input.vertex_radiance = &radiance;
  input.camera = Camera::framing(triangle, 8, 8, 40);
  CHECK_NOTHROW(plugins.create<Renderer>(s.renderer.name, renderer)->render(input));
  CHECK(s.exit.name.empty());  // no exit basis for a lambert material
  CHECK(s.transport.get_int("rays") == 1024);
  CHECK(s.transport.get_string("directions") == "fibonacci");
  CHECK(s.albedo().x() == Approx(0.8f));
  CHECK(s.bake_path() == fs::path("scene.h5"));
  CHECK(s.load_mesh().vertex_count() == 642);
}

TEST_CASE("a misspelt plug-in key is reported in compiler style", "[scene]") {
  REQUIRE_THROWS_WITH(
      parse("[mesh]\ngenerate = \"sphere\"\n[lighting]\nconstant = 1\n[basis]\nplugin = "
            "\"sh\"\nordr = 10\n"),
      Catch::Contains(
          "scene.toml:7:1: error: basis \"sh\": unknown parameter \"ordr\"; valid: order "
          "(did you mean \"order\"?)"));
}

TEST_CASE("scene errors name the place and the valid choices", "[scene]") {
  CHECK_THROWS_WITH(parse(kValid + "[transport]\nrays = -5\n"),
                    Catch::Contains("scene.toml:9:1") && Catch::Contains("out of range"));
  CHECK_THROWS_WITH(parse(kValid + "[transport]\ndirections = \"fibonaci\"\n"),
                    Catch::Contains("did you mean \"fibonacci\""));
  CHECK_THROWS_WITH(parse(kValid + "[transport]\nshadowed = \"yes\"\n"),
                    Catch::Contains("must be a bool"));
  CHECK_THROWS_WITH(
      parse(kValid + "[lightning]\nintensity = 2\n"),
      Catch::Contains("unknown section [lightning]") && Catch::Contains("did you mean [lighting]"));
  CHECK_THROWS_WITH(
      parse("[mesh]\ngenerate = \"sphere\"\n[lighting]\nconstant = 1\n[basis]\nplugin = \"shh\"\n"),
      Catch::Contains("scene.toml:6:10") &&
          Catch::Contains("no basis plug-in named \"shh\"; available: ") &&
          Catch::Contains(", sh") && Catch::Contains("did you mean \"sh\""));
  CHECK_THROWS_WITH(parse("[mesh]\nfile = \"no/such/bunny.off\"\n[lighting]\nconstant = 1\n"),
                    Catch::Contains("scene.toml:2:1") && Catch::Contains("not found"));
  CHECK_THROWS_WITH(parse("[mesh]\n[lighting]\nconstant = 1\n"),
                    Catch::Contains("exactly one of \"file\" or \"generate\""));
  CHECK_THROWS_WITH(parse("[mesh]\ngenerate = \"sphere\"\n"),
                    Catch::Contains("give \"environment\", \"constant\" or [[lighting.point]]"));
  CHECK_THROWS_WITH(parse("[mesh]\ngenerate = \"sphere\"\n[lighting]\nconstant = 1\nenvironment = "
                          "\"x.exr\"\n"),
                    Catch::Contains("not both") || Catch::Contains("not found"));
  CHECK_THROWS_WITH(parse("[mesh\ngenerate = 1\n"), Catch::Contains("scene.toml:1"));
  CHECK_THROWS_WITH(SceneSpec::load("/no/such/scene.toml", registry()),
                    Catch::Contains("scene file not found"));
}

TEST_CASE("paths resolve against the scene's folder", "[scene]") {
  const fs::path dir = fs::temp_directory_path() / "prt_scene_paths";
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "t.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  std::ofstream(dir / "s.toml") << "[mesh]\nfile = \"meshes/t.off\"\n[lighting]\nconstant = 1\n"
                                   "[output]\nbake = \"out/x.h5\"\n";
  const SceneSpec s = SceneSpec::load(dir / "s.toml", registry());
  CHECK(s.load_mesh().triangle_count() == 1);
  CHECK(s.bake_path() == dir / "out" / "x.h5");
}
