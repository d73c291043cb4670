// prt subdivide: large test meshes made reproducibly from the real ones, for
// the scale benchmarks (docs/scale.md). Uniform 1-to-4 subdivision (Loop or
// midpoint, OpenMesh's subdividers) while a whole level fits under the target,
// then the longest edges are split one at a time until the mesh has exactly
// the requested vertex count. Nothing random: the same input and target give
// the same file.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/MidpointT.hh>
#include <fstream>
#include <iostream>
#include <queue>
#include <sstream>

#include "commands.hpp"
#include "prt/error.hpp"
#include "prt/memory.hpp"
#include "prt/mesh.hpp"
#include "prt/output_file.hpp"
#include "prt/progress.hpp"

namespace prt::cli {

namespace {

using SubdivisionMesh = OpenMesh::TriMesh_ArrayKernelT<>;

SubdivisionMesh to_openmesh(const Mesh& mesh) {
  SubdivisionMesh out;
  out.reserve(mesh.positions.size(), 3 * mesh.triangles.size(), mesh.triangles.size());
  std::vector<SubdivisionMesh::VertexHandle> handles;
  handles.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) handles.push_back(out.add_vertex({p.x(), p.y(), p.z()}));
  for (const auto& t : mesh.triangles) out.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  return out;
}

// Splits the longest edge (ties: the lower edge index) at its midpoint until
// the mesh has `target` vertices.
void split_longest_edges(SubdivisionMesh& mesh, std::size_t target) {
  using Entry = std::pair<float, int>;  // length, edge index
  const auto length = [&](SubdivisionMesh::EdgeHandle e) { return mesh.calc_edge_length(e); };
  const auto later = [](const Entry& a, const Entry& b) {
    return a.first != b.first ? a.first < b.first : a.second > b.second;
  };
  std::priority_queue<Entry, std::vector<Entry>, decltype(later)> queue(later);
  for (auto e : mesh.edges()) queue.push({length(e), e.idx()});
  while (mesh.n_vertices() < target && !queue.empty()) {
    const auto [stored, index] = queue.top();
    queue.pop();
    const SubdivisionMesh::EdgeHandle edge(index);
    if (length(edge) != stored) continue;  // shortened by an earlier split: stale
    const std::size_t edges_before = mesh.n_edges();
    const auto h = mesh.halfedge_handle(edge, 0);
    const auto middle =
        0.5f * (mesh.point(mesh.from_vertex_handle(h)) + mesh.point(mesh.to_vertex_handle(h)));
    mesh.split(edge, middle);
    queue.push({length(edge), index});
    for (std::size_t e = edges_before; e < mesh.n_edges(); ++e) {
      const SubdivisionMesh::EdgeHandle added(static_cast<int>(e));
      queue.push({length(added), static_cast<int>(e)});
    }
  }
}

// Peak resident bytes per vertex of the result (OpenMesh's mesh, one Loop
// level's temporaries, the split queue, the encoded file): bunny00.off to
// 10^6 vertices peaked at 276 MB and to 4 x 10^6 at 873 MB (/usr/bin/time),
// so 400 leaves a margin for meshes that subdivide less evenly.
constexpr double kBytesPerVertex = 400;
// Vertex indices are 32-bit in OpenMesh and in the bake file.
constexpr std::size_t kMaxVertices = std::size_t(1) << 31;

// Refuses, before any work, a target this process cannot hold.
void require_memory_for(std::size_t vertices) {
  if (vertices >= kMaxVertices)
    throw Error("--vertices " + std::to_string(vertices) + ": meshes are limited to " +
                std::to_string(kMaxVertices - 1) + " vertices (32-bit indices)");
  const double needed = kBytesPerVertex * double(vertices), available = available_memory();
  if (needed > available)
    throw Error("--vertices " + std::to_string(vertices) + ": the subdivided mesh needs about " +
                gigabytes(needed) + " of memory, and " + gigabytes(available) +
                " is available; ask for fewer vertices");
}

// One uniform 1-to-4 level. OpenMesh's subdividers detach in their
// destructor through a virtual call, which aborts the process ("pure virtual
// method called") when it runs during unwinding: detach before that.
template <class Subdivider>
void subdivide_once(SubdivisionMesh& mesh) {
  Subdivider subdivider;
  subdivider.attach(mesh);
  try {
    subdivider(1);
  } catch (...) {
    subdivider.detach();
    throw;
  }
  subdivider.detach();
}

}  // namespace

namespace {

int subdivide_checked(const SubdivideArgs& args) {
  const std::filesystem::path output = args.output;
  const std::string extension = output.extension().string();
  if (extension != ".ply" && extension != ".off" && extension != ".obj")
    throw Error(args.output + ": the output must be .ply (binary), .off or .obj");
  if (args.scheme != "loop" && args.scheme != "midpoint")
    throw Error("--scheme: \"" + args.scheme + "\" is not loop or midpoint");
  check_output({output, FileKind::other, "mesh"}, {args.input}, args.force);
  require_memory_for(args.vertices);
  const Mesh source = load_mesh(args.input);
  if (args.vertices < source.positions.size())
    throw Error("--vertices " + std::to_string(args.vertices) + " is below the input's " +
                std::to_string(source.positions.size()) + " vertices");
  SubdivisionMesh mesh = to_openmesh(source);
  Stopwatch clock;
  int levels = 0;
  // A 1-to-4 level adds a vertex per edge.
  while (mesh.n_vertices() + mesh.n_edges() <= args.vertices) {
    if (args.scheme == "loop")
      subdivide_once<OpenMesh::Subdivider::Uniform::LoopT<SubdivisionMesh>>(mesh);
    else
      subdivide_once<OpenMesh::Subdivider::Uniform::MidpointT<SubdivisionMesh>>(mesh);
    ++levels;
  }
  const std::size_t uniform = mesh.n_vertices();
  split_longest_edges(mesh, args.vertices);
  mesh.garbage_collection();
  OpenMesh::IO::Options options;
  if (extension == ".ply") options += OpenMesh::IO::Options::Binary;
  std::ostringstream encoded;
  if (!OpenMesh::IO::write_mesh(mesh, encoded, extension, options))
    throw Error(args.output + ": OpenMesh could not encode the subdivided mesh");
  const std::string bytes = std::move(encoded).str();
  write_atomically(output, [&](const std::filesystem::path& temporary) {
    write_bytes_checked(temporary, bytes.data(), bytes.size(), output);
  });
  std::cout << args.input << ": " << source.positions.size() << " vertices -> " << levels << " "
            << args.scheme << " level(s) (" << uniform << ") + " << mesh.n_vertices() - uniform
            << " longest-edge splits = " << mesh.n_vertices() << " vertices, " << mesh.n_faces()
            << " triangles -> " << args.output << " (" << clock.seconds() << " s)\n";
  return 0;
}

}  // namespace

// The estimate leaves a margin, but a mesh that subdivides unevenly or a
// tight ulimit may still run out: say so in the command's own terms.
int subdivide(const SubdivideArgs& args) {
  try {
    return subdivide_checked(args);
  } catch (const std::bad_alloc&) {
    throw Error("--vertices " + std::to_string(args.vertices) +
                ": out of memory while subdividing (" + gigabytes(available_memory()) +
                " available now); ask for fewer vertices");
  }
}

}  // namespace prt::cli
