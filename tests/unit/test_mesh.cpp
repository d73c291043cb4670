#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "prt/error.hpp"
#include "prt/mesh.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {
fs::path write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "prt_mesh_tests";
  fs::create_directories(dir);
  const fs::path file = dir / name;
  std::ofstream(file) << text;
  return file;
}
const char* kTetra = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
}  // namespace

TEST_CASE("generated meshes are valid with unit normals", "[mesh]") {
  for (const Mesh& m : {make_sphere(0), make_sphere(3), make_plane(4), make_box()}) {
    REQUIRE_NOTHROW(m.validate("generated"));
    for (const auto& n : m.normals) CHECK(n.norm() == Approx(1.0f).epsilon(1e-5));
  }
  CHECK(make_sphere(2).vertex_count() == 162);
  CHECK(make_box().triangle_count() == 12);
}

TEST_CASE("area-weighted normals point outward on a closed mesh", "[mesh]") {
  Mesh m = make_sphere(2);
  const auto exact = m.normals;
  m.compute_normals();
  for (std::size_t v = 0; v < m.vertex_count(); ++v) CHECK(m.normals[v].dot(exact[v]) > 0.99f);
}

TEST_CASE("area weighting: a large face dominates a small one", "[mesh]") {
  Mesh m;
  m.positions = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 0.1f}, {0.1f, 0, 0}};
  m.triangles = {{0, 1, 2}, {0, 4, 3}};  // big in z = 0 (normal +z), tiny in y = 0 (normal +y)
  m.compute_normals();
  CHECK(m.normals[0].z() > 0.99f);
}

TEST_CASE("OFF, OBJ, PLY and STL files load", "[mesh]") {
  const Mesh off = load_mesh(write_temp("tetra.off", kTetra));
  CHECK(off.vertex_count() == 4);
  CHECK(off.triangle_count() == 4);
  const Mesh obj = load_mesh(write_temp(
      "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n"));
  CHECK(obj.triangle_count() == 1);
  CHECK(obj.normals[0].z() == Approx(1.0f));
  const Mesh ply = load_mesh(write_temp(
      "tri.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty "
      "float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 "
      "0\n0 1 0\n3 0 1 2\n"));
  CHECK(ply.triangle_count() == 1);
  const Mesh stl = load_mesh(write_temp(
      "tri.stl",
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
      "endfacet\nendsolid t\n"));
  CHECK(stl.triangle_count() == 1);
}

TEST_CASE("bad meshes are reported clearly", "[mesh][extremes]") {
  CHECK_THROWS_WITH(load_mesh("/nonexistent/bunny.off"), Catch::Contains("not found"));
  CHECK_THROWS_WITH(load_mesh(write_temp("empty.off", "OFF\n0 0 0\n")),
                    Catch::Contains("no surface"));
  CHECK_THROWS_WITH(
      load_mesh(write_temp("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")),
      Catch::Contains("nan.off:4") && Catch::Contains("NaN"));
  CHECK_THROWS_WITH(
      load_mesh(write_temp("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n")),
      Catch::Contains("inf.off:5"));
  // An index past the vertex count is never silently accepted.
  CHECK_THROWS_WITH(
      load_mesh(write_temp("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")),
      Catch::Contains("range.off:6") &&
          Catch::Contains("vertex index \"7\", but the file declares 3 vertices"));
  CHECK_THROWS_WITH(load_mesh(write_temp("garbage.off", "this is not a mesh\n")),
                    Catch::Contains("garbage.off"));
}

TEST_CASE("degenerate faces are skipped and counted", "[mesh][extremes]") {
  // Face 2 repeats a vertex, face 3 is collinear (zero area).
  const Mesh m = load_mesh(
      write_temp("degenerate.off",
                 "OFF\n7 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 2 0\n0 3 0\n0 4 0\n3 0 1 2\n3 1 0 3\n"
                 "3 0 0 2\n3 4 5 6\n"));
  CHECK(m.triangle_count() == 2);
  CHECK(m.skipped_degenerate_faces == 2);
}
