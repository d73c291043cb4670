// A texel atlas for a mesh that has none: CGAL's as-rigid-as-possible map.
#pragma once
#include <string>

#include "prt/mesh.hpp"

namespace prt {

// Sets mesh.uvs: one chart, CGAL's ARAP parameterisation (free border),
// scaled uniformly into the unit square. The mesh must be a topological disk
// (connected, one border, no handles) and the map must not fold; otherwise
// throws prt::Error naming `source` and what to do (give the file an atlas:
// OBJ vt, PLY u v).
void compute_atlas(Mesh& mesh, const std::string& source);

}  // namespace prt
