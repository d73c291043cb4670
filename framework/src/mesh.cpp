#include "prt/mesh.hpp"

#include <Eigen/Geometry>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <tuple>

#include "mesh_file_check.hpp"
#include "prt/error.hpp"
#include "prt/log.hpp"

namespace prt {

namespace {

using OMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// Captures what OpenMesh prints to its error log while a file is read, so
// problems can be reported in one message instead of a stream of warnings.
// The capture stream is connected once for the process: OpenMesh's
// mostream::disconnect leaks the wrapper that connect allocated.
class OpenMeshLogCapture {
 public:
  OpenMeshLogCapture() : lock_(mutex()) {
    static std::ostringstream& log = []() -> std::ostringstream& {
      static std::ostringstream stream;
      omerr().disconnect(std::cerr);
      omerr().connect(stream);
      omlog().disable();
      return stream;
    }();
    log_ = &log;
    log_->str("");
  }
  std::string text() {
    omerr().flush();
    return log_->str();
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::ostringstream* log_ = nullptr;
};

std::size_t count_lines_containing(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1))
    ++count;
  return count;
}

// OpenMesh reads "nan" or "inf" in a text file as garbage without a word, so
// text files are scanned for non-finite numbers first.
void reject_non_finite_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  char head[512] = {};
  in.read(head, sizeof head);
  if (std::find(head, head + in.gcount(), '\0') != head + in.gcount()) return;  // binary
  in.clear();
  in.seekg(0);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream tokens(line);
    for (std::string token; tokens >> token;) {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end && *end == '\0' && end != token.c_str() && !std::isfinite(value))
        throw Error(file.string() + ":" + std::to_string(number) +
                    ": NaN or infinite coordinate \"" + token + "\"");
    }
  }
}

}  // namespace

Eigen::Vector3f Mesh::bounds_min() const {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY);
  for (const auto& p : positions) lo = lo.cwiseMin(p);
  return lo;
}

Eigen::Vector3f Mesh::bounds_max() const {
  Eigen::Vector3f hi = Eigen::Vector3f::Constant(-INFINITY);
  for (const auto& p : positions) hi = hi.cwiseMax(p);
  return hi;
}

void Mesh::compute_normals() {
  std::vector<Eigen::Vector3d> sum(positions.size(), Eigen::Vector3d::Zero());
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = positions[t[0]].cast<double>(), b = positions[t[1]].cast<double>(),
                          c = positions[t[2]].cast<double>();
    const Eigen::Vector3d area_normal = (b - a).cross(c - a);  // |.| = 2 x area
    for (auto v : t) sum[v] += area_normal;
  }
  normals.resize(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const double length = sum[v].norm();
    normals[v] = length > 0 ? (sum[v] / length).cast<float>() : Eigen::Vector3f(0, 1, 0);
  }
}

void Mesh::validate(const std::string& source) const {
  if (positions.empty() || triangles.empty())
    throw Error(source + ": empty mesh (" + std::to_string(positions.size()) + " vertices, " +
                std::to_string(triangles.size()) + " usable triangles)");
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite())
      throw Error(source + ": vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (auto index : triangles[f])
      if (index >= positions.size())
        throw Error(source + ": face " + std::to_string(f) + " uses vertex index " +
                    std::to_string(index) + ", but the mesh has " +
                    std::to_string(positions.size()) + " vertices");
  if (normals.size() != positions.size())
    throw Error(source + ": " + std::to_string(normals.size()) + " normals for " +
                std::to_string(positions.size()) + " vertices");
  if (!uvs.empty() && uvs.size() != positions.size())
    throw Error(source + ": " + std::to_string(uvs.size()) + " texture coordinates for " +
                std::to_string(positions.size()) + " vertices");
  for (std::size_t v = 0; v < uvs.size(); ++v)
    if (!uvs[v].allFinite())
      throw Error(source + ": vertex " + std::to_string(v) +
                  " has a NaN or infinite texture coordinate");
}

void split_at_uv_seams(Mesh& mesh, const std::vector<std::array<Eigen::Vector2f, 3>>& corner_uvs) {
  std::map<std::tuple<std::uint32_t, float, float>, std::uint32_t> index;
  Mesh split;
  split.skipped_degenerate_faces = mesh.skipped_degenerate_faces;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    std::array<std::uint32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[f][std::size_t(k)];
      const Eigen::Vector2f uv = corner_uvs[f][std::size_t(k)];
      const auto [at, added] =
          index.try_emplace({v, uv.x(), uv.y()}, std::uint32_t(split.positions.size()));
      if (added) {
        split.positions.push_back(mesh.positions[v]);
        split.normals.push_back(mesh.normals[v]);
        split.uvs.push_back(uv);
      }
      t[std::size_t(k)] = at->second;
    }
    split.triangles.push_back(t);
  }
  mesh = std::move(split);
}

namespace {

// OpenMesh opens every material library an OBJ names, relative to the OBJ's
// folder, whatever it is (a FIFO hangs the reader, /dev/zero feeds it without
// end). PRT reads no materials, so an OBJ is read from its own text with its
// "mtllib" statements blanked (line numbers kept): no other file is opened.
std::string obj_text_without_side_files(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string text, line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line.compare(first, 6, "mtllib") == 0 &&
        (line.size() == first + 6 || std::isspace(static_cast<unsigned char>(line[first + 6])))) {
      log_warning(file.string() + ":" + std::to_string(number) + ": \"" +
                  elide(line.substr(first), 60) +
                  "\" not followed: PRT reads no material libraries (the albedo is the scene's "
                  "[material])");
      line = "# (mtllib not followed)";
    }
    text += line;
    text += '\n';
  }
  if (in.bad()) throw Error(file.string() + ": cannot read the mesh file");
  return text;
}

std::string lowercase_extension(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

bool read_openmesh(OMesh& om, const std::filesystem::path& file, OpenMesh::IO::Options& options) {
  if (lowercase_extension(file) != ".obj")
    return OpenMesh::IO::read_mesh(om, file.string(), options);
  std::istringstream text(obj_text_without_side_files(file));
  return OpenMesh::IO::read_mesh(om, text, ".obj", options);
}

// The mesh file through OpenMesh; its log (what OpenMesh said of the file) is
// returned for the checks that follow.
std::string read_with_openmesh(const std::filesystem::path& file, OMesh& om,
                               OpenMesh::IO::Options& options, bool uvs) {
  om.request_vertex_normals();
  options = OpenMesh::IO::Options::VertexNormal;
  if (uvs) {
    om.request_vertex_texcoords2D();
    om.request_halfedge_texcoords2D();
    options += OpenMesh::IO::Options::VertexTexCoord;
    options += OpenMesh::IO::Options::FaceTexCoord;
  }
  OpenMeshLogCapture capture;
  const bool ok = read_openmesh(om, file, options);
  const std::string log = capture.text();
  if (!ok) {
    const std::string detail = log.substr(0, log.find('\n'));
    throw Error(file.string() + ": cannot read mesh" + (detail.empty() ? "" : " (" + detail + ")"));
  }
  return log;
}

// Readers drop some bad faces without a word (binary PLY indices out of
// range or negative): what was read must account for what was declared.
void check_read_counts(const std::filesystem::path& file, const OMesh& om,
                       const DeclaredMeshSize& declared, const std::string& log,
                       std::size_t skipped) {
  const std::string source = file.string();
  if (log.find("invalid vertex index") != std::string::npos)
    throw Error(source + ": " +
                std::to_string(count_lines_containing(log, "invalid vertex index")) +
                " face(s) use a vertex index out of range (the file has " +
                std::to_string(om.n_vertices()) + " vertices)");
  if (declared.known && om.n_vertices() < declared.vertices)
    throw Error(source + ": read " + std::to_string(om.n_vertices()) + " of the " +
                std::to_string(declared.vertices) + " vertices its header declares");
  if (declared.known && om.n_faces() + skipped < declared.faces) {
    // STL stores corners, not indices: a dropped facet there repeats a corner
    // (after OpenMesh merges equal positions) or cannot join the surface.
    const bool corners = lowercase_extension(file).rfind(".stl", 0) == 0;
    throw Error(source + ": " + std::to_string(declared.faces - om.n_faces() - skipped) +
                " of its " + std::to_string(declared.faces) + " faces could not be read (" +
                (corners ? "facets whose corners coincide, or that would make an edge shared "
                           "by more than two faces?"
                         : "vertex indices out of range or negative?") +
                ")");
  }
}

// Triangles with a non-zero area; the others are counted as skipped. With
// `corner_uvs`, each kept triangle's texture coordinates (per face corner
// where the file gives them so, else per vertex).
void add_triangles(const OMesh& om, Mesh& mesh, const OpenMesh::IO::Options& options,
                   std::vector<std::array<Eigen::Vector2f, 3>>* corner_uvs) {
  for (auto fh : om.faces()) {
    std::array<std::uint32_t, 3> t{};
    std::array<Eigen::Vector2f, 3> uv{};
    int k = 0;
    for (auto hh : om.fh_range(fh)) {
      const auto vh = om.to_vertex_handle(hh);
      if (corner_uvs) {
        const auto& c = options.check(OpenMesh::IO::Options::FaceTexCoord) ? om.texcoord2D(hh)
                                                                           : om.texcoord2D(vh);
        uv[std::size_t(k)] = {c[0], c[1]};
      }
      t[std::size_t(k++)] = static_cast<std::uint32_t>(vh.idx());
    }
    const Eigen::Vector3f a = mesh.positions[t[0]], b = mesh.positions[t[1]],
                          c = mesh.positions[t[2]];
    if (!((b - a).cross(c - a).squaredNorm() > 0.f)) {
      ++mesh.skipped_degenerate_faces;
      continue;
    }
    mesh.triangles.push_back(t);
    if (corner_uvs) corner_uvs->push_back(uv);
  }
}

// The file's normals when every one is usable (finite, not zero), normalised;
// else none (the mesh computes its own).
void add_file_normals(const OMesh& om, const OpenMesh::IO::Options& options, Mesh& mesh) {
  if (!options.check(OpenMesh::IO::Options::VertexNormal)) return;
  for (auto vh : om.vertices()) {
    const auto& n = om.normal(vh);
    mesh.normals.emplace_back(n[0], n[1], n[2]);
  }
  bool usable = true;
  for (auto& n : mesh.normals) {
    const float length = n.norm();
    if (!std::isfinite(length) || length < 1e-12f)
      usable = false;
    else
      n /= length;
  }
  if (!usable) mesh.normals.clear();
}

}  // namespace

Mesh load_mesh(const std::filesystem::path& file, bool uvs) {
  const std::string source = file.string();
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  if (!std::filesystem::exists(status)) throw Error(source + ": mesh file not found");
  if (!std::filesystem::is_regular_file(status))
    throw Error(source + ": the mesh is " +
                (std::filesystem::is_directory(status) ? "a directory" : "not a regular file") +
                "; name a mesh file");
  const DeclaredMeshSize declared = check_mesh_file(file);
  reject_non_finite_text(file);
  OMesh om;
  OpenMesh::IO::Options options;
  const std::string log = read_with_openmesh(file, om, options, uvs);
  const bool has_uvs = uvs && (options.check(OpenMesh::IO::Options::FaceTexCoord) ||
                               options.check(OpenMesh::IO::Options::VertexTexCoord));
  Mesh mesh;
  mesh.positions.reserve(om.n_vertices());
  for (auto vh : om.vertices()) {
    const auto& p = om.point(vh);
    mesh.positions.emplace_back(p[0], p[1], p[2]);
  }
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    if (!mesh.positions[v].allFinite())
      throw Error(source + ": vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
  // Faces OpenMesh refused (a vertex repeated) count as degenerate.
  mesh.skipped_degenerate_faces = count_lines_containing(log, "ImporterT: Face");
  check_read_counts(file, om, declared, log, mesh.skipped_degenerate_faces);
  if (const auto complex = count_lines_containing(log, "complex"))
    log_warning(source + ": " + std::to_string(complex) +
                " non-manifold face(s); OpenMesh duplicated their vertices");
  std::vector<std::array<Eigen::Vector2f, 3>> corner_uvs;
  add_triangles(om, mesh, options, has_uvs ? &corner_uvs : nullptr);
  add_file_normals(om, options, mesh);
  if (mesh.normals.empty()) mesh.compute_normals();
  // Normals first, over the whole surface: a seam does not crease the shading.
  if (has_uvs) split_at_uv_seams(mesh, corner_uvs);
  mesh.validate(source);
  if (mesh.skipped_degenerate_faces > 0)
    log_warning(source + ": skipped " + std::to_string(mesh.skipped_degenerate_faces) +
                " degenerate face(s)");
  return mesh;
}

Mesh make_sphere(int subdivisions, float radius) {
  Mesh m;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.positions) p.normalize();
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      const auto index = static_cast<std::uint32_t>(m.positions.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& f : m.triangles) {
      const auto ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  m.normals = m.positions;  // exact normals of the unit sphere
  for (auto& p : m.positions) p *= radius;
  return m;
}

Mesh make_plane(int cells, float size) {
  Mesh m;
  const int n = std::max(cells, 1);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.emplace_back(size * (float(i) / n - 0.5f), 0.f, size * (float(j) / n - 0.5f));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + (n + 1), d = c + 1;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  m.normals.assign(m.positions.size(), Eigen::Vector3f(0, 1, 0));
  return m;
}

Mesh make_box(float size) {
  // Each face has its own 4 vertices so normals are the face normals.
  Mesh m;
  const float h = size / 2;
  const Eigen::Vector3f axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {1.f, -1.f}) {
      const Eigen::Vector3f n = sign * axes[axis];
      const Eigen::Vector3f u = axes[(axis + 1) % 3], v = sign * axes[(axis + 2) % 3];
      const auto base = static_cast<std::uint32_t>(m.positions.size());
      for (auto [a, b] : {std::pair{-1.f, -1.f}, {1.f, -1.f}, {1.f, 1.f}, {-1.f, 1.f}}) {
        m.positions.push_back(h * (n + a * u + b * v));
        m.normals.push_back(n);
      }
      m.triangles.push_back({base, base + 1, base + 2});
      m.triangles.push_back({base, base + 2, base + 3});
    }
  return m;
}

Mesh make_open_box(int cells, float size) {
  // Five gridded faces (no top), each with its own vertices and inward normals.
  Mesh m;
  const float h = size / 2;
  const int n = std::max(cells, 1);
  const Eigen::Vector3f axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {1.f, -1.f}) {
      if (axis == 1 && sign > 0) continue;  // the open top
      const Eigen::Vector3f out = sign * axes[axis];
      const Eigen::Vector3f u = axes[(axis + 1) % 3], v = sign * axes[(axis + 2) % 3];
      const auto base = static_cast<std::uint32_t>(m.positions.size());
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          const float a = 2.f * i / n - 1.f, b = 2.f * j / n - 1.f;
          m.positions.push_back(h * (out + a * u + b * v));
          m.normals.push_back(-out);
        }
      auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(i * (n + 1) + j); };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
          m.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
        }
    }
  return m;
}

Mesh make_generated(const std::string& name, int detail) {
  if (name == "sphere") return make_sphere(detail);
  if (name == "plane") return make_plane(std::max(detail, 1));
  if (name == "box") return make_box();
  if (name == "open-box") return make_open_box(4 << std::min(detail, 4));
  if (name == "room") return make_room(detail);
  throw Error("unknown generated mesh \"" + name + "\"; valid: sphere, plane, box, open-box, room");
}

}  // namespace prt
