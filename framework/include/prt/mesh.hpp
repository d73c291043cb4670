// Triangle meshes: loaded through OpenMesh (OFF, OBJ, PLY, STL) or generated.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace prt {

struct Mesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;  // unit length, one per vertex
  std::vector<std::array<std::uint32_t, 3>> triangles;
  // A texel atlas: empty, or one (u, v) in [0, 1]^2 per vertex. A vertex on
  // a seam between charts is one vertex per chart (split_at_uv_seams).
  std::vector<Eigen::Vector2f> uvs;
  std::size_t skipped_degenerate_faces = 0;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size(); }
  Eigen::Vector3f bounds_min() const;
  Eigen::Vector3f bounds_max() const;

  // Area-weighted vertex normals from the triangles.
  void compute_normals();
  // Throws prt::Error naming the first NaN/Inf coordinate, out-of-range index,
  // missing normal or bad uv; `source` is used in the message.
  void validate(const std::string& source) const;
};

// Loads a mesh; keeps normals stored in the file, else computes them.
// Degenerate faces (zero area, repeated vertex) are skipped and counted.
// With `uvs`, the file's texture coordinates too (OBJ vt per face corner,
// PLY u, v or s, t per vertex) when it has them, the mesh split at their seams.
Mesh load_mesh(const std::filesystem::path& file, bool uvs = false);

// One vertex per (vertex, corner uv) pair: `corner_uvs` holds three per
// triangle. Positions and normals are copied, so shading is unchanged.
void split_at_uv_seams(Mesh& mesh, const std::vector<std::array<Eigen::Vector2f, 3>>& corner_uvs);

// Generated meshes for tests that need no download.
Mesh make_sphere(int subdivisions, float radius = 1.0f);  // icosphere, exact normals
Mesh make_plane(int cells, float size = 2.0f);            // in y = 0, normal +y
Mesh make_box(float size = 2.0f);                         // closed cube, outward normals
// A box without its top (+y) face, seen from inside: inward normals, each
// face a grid of cells x cells squares. The concave test scene of inter-reflection.
Mesh make_open_box(int cells, float size = 2.0f);
// A 4 x 2.5 x 4 room with walls 0.2 thick, a ceiling and a window, on an
// 8 x 8 ground (framework/src/mesh_room.cpp): the probe scenes' room. Faces
// are grids of cells 0.8 / 2^detail wide.
Mesh make_room(int detail);

// Builds one of the generated meshes by name ("sphere", "plane", "box", "open-box", "room").
Mesh make_generated(const std::string& name, int detail);

}  // namespace prt
