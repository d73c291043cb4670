// The atlas of a disk-like mesh by CGAL's Surface_mesh_parameterization:
// as-rigid-as-possible (Liu et al. 2008), which keeps areas as well as
// angles (a lightmap's texels stay near one size; CGAL's least-squares
// conformal map, tried first, shrank Three Peaks' triangles by up to 10^6
// and folded 60 of them).
#include "prt/mesh_atlas.hpp"

#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <vector>

#include "prt/error.hpp"

namespace prt {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;
namespace PMP = CGAL::Polygon_mesh_processing;

std::string not_a_disk(const std::string& source, const std::string& why) {
  return source + ": " + why +
         ", so PRT cannot compute its atlas (CGAL's parameterisation needs a topological disk); "
         "give the mesh file texture coordinates (OBJ vt, PLY u v) for texel receivers";
}

// The mesh in CGAL's form, vertex i as vertex i; refuses non-manifold faces.
SurfaceMesh surface_mesh(const Mesh& mesh, const std::string& source) {
  SurfaceMesh sm;
  for (const Eigen::Vector3f& p : mesh.positions) sm.add_vertex({p.x(), p.y(), p.z()});
  for (const auto& t : mesh.triangles)
    if (sm.add_face(SurfaceMesh::Vertex_index(t[0]), SurfaceMesh::Vertex_index(t[1]),
                    SurfaceMesh::Vertex_index(t[2])) == SurfaceMesh::null_face())
      throw Error(not_a_disk(source, "the mesh is not a manifold surface"));
  return sm;
}

void require_disk(SurfaceMesh& sm, const std::string& source) {
  std::vector<SurfaceMesh::Halfedge_index> borders;
  PMP::extract_boundary_cycles(sm, std::back_inserter(borders));
  const auto components = PMP::connected_components(
      sm, sm.add_property_map<SurfaceMesh::Face_index, std::size_t>("f:component", 0).first);
  const long euler =
      long(sm.number_of_vertices()) - long(sm.number_of_edges()) + long(sm.number_of_faces());
  if (borders.empty()) throw Error(not_a_disk(source, "the mesh is closed (it has no border)"));
  if (components != 1 || borders.size() != 1 || euler != 1)
    throw Error(not_a_disk(source, "the mesh has " + std::to_string(components) +
                                       " connected part(s), " + std::to_string(borders.size()) +
                                       " border(s) and Euler characteristic " +
                                       std::to_string(euler) + " (a disk has 1, 1 and 1)"));
}

// A map that turns some triangles over folds the chart onto itself: texels
// there would hold two places' light.
void require_no_folds(const Mesh& mesh, const std::string& source) {
  std::size_t positive = 0, negative = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector2f a = mesh.uvs[t[0]], b = mesh.uvs[t[1]], c = mesh.uvs[t[2]];
    const float area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    positive += area > 0, negative += area < 0;
  }
  if (std::min(positive, negative) > 0)
    throw Error(source + ": CGAL's parameterisation turns " +
                std::to_string(std::min(positive, negative)) + " of its " +
                std::to_string(mesh.triangles.size()) +
                " triangles over (the chart folds onto itself); give the mesh file texture "
                "coordinates (OBJ vt, PLY u v) for texel receivers");
}

}  // namespace

void compute_atlas(Mesh& mesh, const std::string& source) {
  SurfaceMesh sm = surface_mesh(mesh, source);
  // Isolated vertices (used by no face) have no place in a chart.
  for (auto v : sm.vertices())
    if (sm.is_isolated(v))
      throw Error(
          not_a_disk(source, "vertex " + std::to_string(std::size_t(v)) + " lies on no face"));
  require_disk(sm, source);
  const auto border = PMP::longest_border(sm).first;
  auto uv = sm.add_property_map<SurfaceMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  const SMP::Error_code status =
      SMP::parameterize(sm, SMP::ARAP_parameterizer_3<SurfaceMesh>(), border, uv);
  if (status != SMP::OK)
    throw Error(source + ": CGAL's conformal map failed (" + SMP::get_error_message(status) + ")");
  // Uniform scale into [0, 1]^2, centred along the shorter side.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (auto v : sm.vertices()) {
    const Eigen::Vector2d p(uv[v].x(), uv[v].y());
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  const double side = (hi - lo).maxCoeff();
  if (!(side > 0) || !std::isfinite(side))
    throw Error(source + ": CGAL's conformal map collapsed the mesh to a point");
  const Eigen::Vector2d shift = lo - 0.5 * (Eigen::Vector2d::Constant(side) - (hi - lo));
  mesh.uvs.resize(mesh.positions.size());
  for (auto v : sm.vertices()) {
    const Eigen::Vector2d p = (Eigen::Vector2d(uv[v].x(), uv[v].y()) - shift) / side;
    mesh.uvs[std::size_t(v)] = p.cwiseMax(0.0).cwiseMin(1.0).cast<float>();
  }
  require_no_folds(mesh, source);
}

}  // namespace prt
