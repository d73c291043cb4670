// Texels: the atlas (read from a file or computed by CGAL), its texels and
// their points, the radiance texture, texel scenes and their bake files.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "prt/bake.hpp"
#include "prt/mesh_atlas.hpp"
#include "prt/receivers.hpp"
#include "prt/relighting.hpp"
#include "prt/texel_atlas.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {

PluginRegistry& registry() {
  static PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  return r;
}

// The unit square of y = 0 as two triangles, uv = (x, z) scaled by `scale`.
Mesh square(float scale = 1) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}};
  m.compute_normals();
  for (const auto& p : m.positions) m.uvs.emplace_back(scale * p.x(), scale * p.z());
  return m;
}

// A floor (y = 0, x and z in [-1, 1]) and a wall on its z = -1 edge, 2 high,
// sharing that edge: one surface, a topological disk. `cells` per side.
std::string floor_and_wall_off(int cells) {
  std::ostringstream off;
  const int n = cells, columns = n + 1;
  off << "OFF\n" << columns * (2 * n + 1) << " " << 2 * n * 2 * n << " 0\n";
  // Rows 0..n: the wall from its top (y = 2) down to the floor's edge; rows
  // n..2n: the floor from z = -1 to z = 1 (row n shared).
  for (int r = 0; r <= 2 * n; ++r)
    for (int c = 0; c <= n; ++c) {
      const float x = -1 + 2.f * c / n;
      if (r <= n)
        off << x << " " << 2 - 2.f * r / n << " -1\n";
      else
        off << x << " 0 " << -1 + 2.f * (r - n) / n << "\n";
    }
  for (int r = 0; r < 2 * n; ++r)
    for (int c = 0; c < n; ++c) {
      const int a = r * columns + c, b = a + 1, d = a + columns, e = d + 1;
      off << "3 " << a << " " << d << " " << e << "\n3 " << a << " " << e << " " << b << "\n";
    }
  return off.str();
}

}  // namespace

TEST_CASE("the texels of an atlas: every texel a chart covers, with its surface point",
          "[texels]") {
  const TexelSamples full = texel_samples(square(), 8, "square");
  REQUIRE(full.atlas.texels.size() == 64);
  CHECK(full.atlas.width == 8);
  for (std::size_t i = 0; i < 64; ++i) {
    const float x = (full.atlas.texels[i] % 8 + 0.5f) / 8,
                z = (full.atlas.texels[i] / 8 + 0.5f) / 8;
    CHECK((full.points.positions[i] - Eigen::Vector3f(x, 0, z)).norm() < 1e-5f);
    CHECK((full.points.normals[i] - Eigen::Vector3f(0, 1, 0)).norm() < 1e-5f);
  }
  // A chart over a quarter of the texture: its 16 texels, and the ring of
  // texels its border reaches into (bilinear lookups at the border read
  // them), their points clamped onto the chart's edge; the rest skipped.
  const TexelSamples quarter = texel_samples(square(0.5f), 8, "square");
  CHECK(quarter.atlas.texels.size() == 25);
  CHECK(std::find(quarter.atlas.texels.begin(), quarter.atlas.texels.end(), 6u * 8 + 6) ==
        quarter.atlas.texels.end());
  for (const Eigen::Vector3f& p : quarter.points.positions)
    CHECK((p.x() <= 1 + 1e-6f && p.z() <= 1 + 1e-6f));
}

TEST_CASE("texel atlases that cannot hold transfer are refused, each with its reason", "[texels]") {
  Mesh none = square();
  none.uvs.clear();
  CHECK_THROWS_WITH(texel_samples(none, 8, "plain.off"),
                    Catch::Contains("plain.off") && Catch::Contains("no texture coordinates"));
  Mesh tiled = square(2.0f);
  CHECK_THROWS_WITH(texel_samples(tiled, 8, "tiled.obj"), Catch::Contains("outside [0, 1]"));
  // Two squares at different heights on the same uvs (a mirrored or shared chart).
  Mesh twice = square();
  Mesh upper = square();
  for (auto& p : upper.positions) p.y() = 1;
  for (auto t : upper.triangles) {
    for (auto& v : t) v += 4;
    twice.triangles.push_back(t);
  }
  twice.positions.insert(twice.positions.end(), upper.positions.begin(), upper.positions.end());
  twice.normals.insert(twice.normals.end(), upper.normals.begin(), upper.normals.end());
  twice.uvs.insert(twice.uvs.end(), upper.uvs.begin(), upper.uvs.end());
  CHECK_THROWS_WITH(texel_samples(twice, 8, "shared.obj"),
                    Catch::Contains("shared.obj") && Catch::Contains("overlaps itself") &&
                        Catch::Contains(": 64 texel(s)"));  // each texel counted once
  CHECK_THROWS_WITH(texel_samples(square(), 0, "square"), Catch::Contains("resolution"));
}

TEST_CASE("the radiance texture looks linear light up exactly and dilates past its charts",
          "[texels]") {
  const TexelSamples quarter = texel_samples(square(0.5f), 8, "square");
  Eigen::MatrixX3f rows(Eigen::Index(quarter.atlas.texels.size()), 3);
  auto linear = [](float u, float v) { return 2 * u - 3 * v + 4; };
  for (std::size_t i = 0; i < quarter.atlas.texels.size(); ++i) {
    const float u = (quarter.atlas.texels[i] % 8 + 0.5f) / 8,
                v = (quarter.atlas.texels[i] / 8 + 0.5f) / 8;
    rows.row(Eigen::Index(i)).setConstant(linear(u, v));
  }
  const RadianceTexture texture = radiance_texture(quarter.atlas, rows);
  for (const Eigen::Vector2f uv :
       {Eigen::Vector2f(0.1f, 0.2f), Eigen::Vector2f(0.49f, 0.49f), Eigen::Vector2f(0.3f, 0.0f)})
    CHECK(texture.lookup(uv).x() ==
          Approx(linear(std::max(uv.x(), 0.0625f), std::max(uv.y(), 0.0625f))).epsilon(1e-5));
  // Two passes of dilation: texels 1 and 2 past the ring are filled, 3 past is not.
  const auto at = [&](int x, int y) { return texture.texels[std::size_t(y) * 8 + x].x(); };
  CHECK(at(5, 2) > 0);
  CHECK(at(6, 6) > 0);
  CHECK(at(7, 7) == 0);
  CHECK_THROWS_WITH(radiance_texture(quarter.atlas, Eigen::MatrixX3f::Zero(3, 3)),
                    Catch::Contains("3 radiance rows for 25 texels"));
}

TEST_CASE("an OBJ's texture coordinates are read per corner and its vertices split at seams",
          "[texels]") {
  const fs::path file = fs::temp_directory_path() / "prt_seams.obj";
  // Two triangles sharing an edge, each with its own chart: the shared
  // edge's two vertices have two uvs each.
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\n"
                         "vt 0 0\nvt 0.4 0\nvt 0.4 0.4\nvt 0.6 0.6\nvt 1 1\nvt 0.6 1\n"
                         "f 1/1 3/3 2/2\nf 1/4 4/6 3/5\n";
  const Mesh plain = load_mesh(file);
  CHECK(plain.vertex_count() == 4);
  CHECK(plain.uvs.empty());
  const Mesh split = load_mesh(file, true);
  CHECK(split.vertex_count() == 6);
  REQUIRE(split.uvs.size() == 6);
  CHECK(split.triangle_count() == 2);
  for (std::size_t f = 0; f < 2; ++f)
    for (int k = 0; k < 3; ++k)
      CHECK(split.positions[split.triangles[f][std::size_t(k)]] ==
            plain.positions[plain.triangles[f][std::size_t(k)]]);
  CHECK(split.uvs[split.triangles[1][1]].isApprox(Eigen::Vector2f(0.6f, 1)));
  CHECK(texel_samples(split, 16, "seams").atlas.texels.size() > 40);
  fs::remove(file);
  // PLY: u v per vertex (OpenMesh also reads s t).
  const fs::path ply = fs::temp_directory_path() / "prt_uvs.ply";
  std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty "
                        "float y\nproperty float z\nproperty float u\nproperty float v\n"
                        "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0 0.1 0.1\n1 0 0 0.9 0.1\n1 0 1 0.9 0.9\n0 0 1 0.1 0.9\n"
                        "3 0 2 1\n3 0 3 2\n";
  const Mesh quad = load_mesh(ply, true);
  REQUIRE(quad.uvs.size() == 4);
  for (std::size_t v = 0; v < 4; ++v)  // uv = (0.1 + 0.8 x, 0.1 + 0.8 z) at every corner
    CHECK(quad.uvs[v].isApprox(
        Eigen::Vector2f(0.1f + 0.8f * quad.positions[v].x(), 0.1f + 0.8f * quad.positions[v].z())));
  fs::remove(ply);
}

TEST_CASE("CGAL's atlas maps a disk into the unit square and refuses other shapes", "[texels]") {
  Mesh plane = make_plane(4);
  compute_atlas(plane, "plane");
  REQUIRE(plane.uvs.size() == plane.vertex_count());
  float lo = 1, hi = 0;
  for (const auto& uv : plane.uvs)
    lo = std::min(lo, uv.minCoeff()), hi = std::max(hi, uv.maxCoeff());
  CHECK(lo == Approx(0).margin(1e-5));
  CHECK(hi == Approx(1).margin(1e-5));
  // As rigid as possible on a flat square: a similarity, so every distance scales alike.
  const float scale =
      (plane.uvs[1] - plane.uvs[0]).norm() / (plane.positions[1] - plane.positions[0]).norm();
  for (std::size_t v = 2; v < plane.vertex_count(); ++v)
    CHECK((plane.uvs[v] - plane.uvs[0]).norm() ==
          Approx(scale * (plane.positions[v] - plane.positions[0]).norm()).margin(1e-4));
  Mesh ball = make_sphere(1);
  CHECK_THROWS_WITH(compute_atlas(ball, "ball.off"), Catch::Contains("ball.off") &&
                                                         Catch::Contains("closed") &&
                                                         Catch::Contains("OBJ vt"));
  Mesh open = make_open_box(2);
  CHECK_THROWS_WITH(compute_atlas(open, "open.off"), Catch::Contains("5 connected part(s)"));
}

TEST_CASE("a texel scene bakes at its texels, shadowed by its mesh, and reads back", "[texels]") {
  const fs::path dir = fs::temp_directory_path() / "prt_texel_scene";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "floor_wall.off") << floor_and_wall_off(6);
  std::ofstream(dir / "texels.toml") << R"([mesh]
file = "floor_wall.off"
[receivers]
kind = "texels"
resolution = 24
[transport]
rays = 512
[basis]
plugin = "sh"
order = 3
[material]
albedo = [1, 1, 1]
[lighting]
constant = [1, 1, 1]
[camera]
width = 64
height = 48
[output]
bake = "texels.h5"
)";
  const SceneSpec scene = SceneSpec::load(dir / "texels.toml", registry());
  REQUIRE(scene.texels());
  const BakePlan plan = plan_bake(scene, registry());
  StageTimes times;
  RunOptions options;
  options.quiet = true;
  const BakeData baked = bake_to_file(
      scene, plan, {{scene.bake_path(), FileKind::bake, "bake", true}}, options, times);
  REQUIRE(baked.receivers.texels());
  REQUIRE(baked.mesh.uvs.size() == baked.mesh.vertex_count());  // CGAL's atlas
  const std::size_t rows = baked.receiver_count();
  CHECK(std::size_t(baked.transfer.vertices()) == rows);
  CHECK(rows > 24 * 24 / 4);

  // Under constant light the floor's texels by the wall see less sky than
  // those far from it: the rays met the scene's mesh, not the texels' points.
  const Relighting relighting(scene, baked, registry());
  const Eigen::MatrixX3f radiance =
      relighting.relight(baked.compressed, relighting.light(scene.load_environment()), {})
          .vertex_radiance;
  double near = 0, far = 0;
  int near_count = 0, far_count = 0;
  for (std::size_t i = 0; i < rows; ++i) {
    const Eigen::Vector3f& p = baked.receivers.points.positions[i];
    if (p.y() > 1e-4f) continue;  // the wall
    if (p.z() < -0.85f) near += radiance(Eigen::Index(i), 0), ++near_count;
    if (p.z() > 0.7f) far += radiance(Eigen::Index(i), 0), ++far_count;
  }
  REQUIRE(near_count > 0);
  REQUIRE(far_count > 0);
  near /= near_count, far /= far_count;
  CHECK(far > 0.85);
  CHECK(near < 0.85 * far);  // unshadowed (the texels' points as occluders) they would agree

  const BakeData read = read_bake(scene.bake_path());
  CHECK(read.format_version() == kReceiversFormatVersion);
  CHECK(read.receivers.kind == "texels");
  CHECK(read.receivers.atlas.texels == baked.receivers.atlas.texels);
  CHECK(read.receivers.atlas.width == 24);
  CHECK(read.receivers.points.positions == baked.receivers.points.positions);
  CHECK(read.mesh.uvs == baked.mesh.uvs);
  CHECK(read.row_mesh().vertex_count() == rows);
  const Rendered image = render(scene, read, registry(), times);
  CHECK(image.image.width == 64);
  CHECK(std::size_t(image.vertex_radiance.rows()) == rows);
  float brightest = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) brightest = std::max(brightest, image.image.at(x, y)[0]);
  CHECK(brightest > 0.5f);
  fs::remove_all(dir);
}

TEST_CASE("texel scenes refuse what texels do not receive yet, at the key", "[texels]") {
  const fs::path dir = fs::temp_directory_path() / "prt_texel_refusals";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string head =
      "[mesh]\ngenerate = \"plane\"\n[receivers]\nkind = \"texels\"\n"
      "[lighting]\nconstant = [1, 1, 1]\n";
  auto refused = [&](const std::string& extra, const char* expected) {
    std::ofstream(dir / "s.toml") << head << extra;
    CHECK_THROWS_WITH(SceneSpec::load(dir / "s.toml", registry()),
                      Catch::Contains("s.toml:4") && Catch::Contains(expected));
  };
  refused("[transport]\nbounces = 1\n", "inter-reflected light at texels");
  refused("[material]\nbrdf = \"phong\"\n", "glossy transfer at texels");
  refused("[[mesh.add]]\ngenerate = \"sphere\"\n", "one atlas");
  fs::remove_all(dir);
}
