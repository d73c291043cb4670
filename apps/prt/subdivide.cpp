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

#include "commands.hpp"
#include "prt/error.hpp"
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

}  // namespace

int subdivide(const SubdivideArgs& args) {
  const std::filesystem::path output = args.output;
  const std::string extension = output.extension().string();
  if (extension != ".ply" && extension != ".off" && extension != ".obj")
    throw Error(args.output + ": the output must be .ply (binary), .off or .obj");
  if (args.scheme != "loop" && args.scheme != "midpoint")
    throw Error("--scheme: \"" + args.scheme + "\" is not loop or midpoint");
  check_output({output, FileKind::other, "mesh"}, {args.input}, args.force);
  const Mesh source = load_mesh(args.input);
  if (args.vertices < source.positions.size())
    throw Error("--vertices " + std::to_string(args.vertices) + " is below the input's " +
                std::to_string(source.positions.size()) + " vertices");
  SubdivisionMesh mesh = to_openmesh(source);
  Stopwatch clock;
  int levels = 0;
  // A 1-to-4 level adds a vertex per edge.
  while (mesh.n_vertices() + mesh.n_edges() <= args.vertices) {
    if (args.scheme == "loop") {
      OpenMesh::Subdivider::Uniform::LoopT<SubdivisionMesh> loop;
      loop.attach(mesh);
      loop(1);
      loop.detach();
    } else {
      OpenMesh::Subdivider::Uniform::MidpointT<SubdivisionMesh> midpoint;
      midpoint.attach(mesh);
      midpoint(1);
      midpoint.detach();
    }
    ++levels;
  }
  const std::size_t uniform = mesh.n_vertices();
  split_longest_edges(mesh, args.vertices);
  mesh.garbage_collection();
  OpenMesh::IO::Options options;
  if (extension == ".ply") options += OpenMesh::IO::Options::Binary;
  write_atomically(output, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!OpenMesh::IO::write_mesh(mesh, out, extension, options) || !out.flush())
      throw Error(temporary.string() + ": could not write the subdivided mesh");
  });
  std::cout << args.input << ": " << source.positions.size() << " vertices -> " << levels << " "
            << args.scheme << " level(s) (" << uniform << ") + " << mesh.n_vertices() - uniform
            << " longest-edge splits = " << mesh.n_vertices() << " vertices, " << mesh.n_faces()
            << " triangles -> " << args.output << " (" << clock.seconds() << " s)\n";
  return 0;
}

}  // namespace prt::cli
