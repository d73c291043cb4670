// Overdraw of a clustering (Sloan et al. 2003, "Clustered Principal
// Components for Precomputed Radiance Transfer", section 5): a triangle whose
// vertices lie in c distinct clusters is drawn c times; superclusters draw
// a group of clusters as one, so a triangle is drawn once per distinct
// supercluster. Reclassification and superclustering, which reduce it, are
// in plugins/compressor/clustering/reclassification.cpp and superclusters.cpp.
#include "prt/compressor.hpp"

namespace prt {

double average_overdraw(const Mesh& mesh, const std::vector<std::int32_t>& id) {
  if (mesh.triangles.empty()) return 0.0;
  double sum = 0;
  for (const auto& t : mesh.triangles) {
    const std::int32_t a = id[t[0]], b = id[t[1]], c = id[t[2]];
    sum += 1 + (b != a) + (c != a && c != b);
  }
  return sum / double(mesh.triangles.size());
}

std::vector<std::int32_t> supercluster_of_vertex(const CompressedTransfer& c) {
  if (c.supercluster_of_cluster.empty()) return c.cluster_of_vertex;
  std::vector<std::int32_t> out(c.cluster_of_vertex.size());
  for (std::size_t p = 0; p < out.size(); ++p)
    out[p] = c.supercluster_of_cluster[c.cluster_of_vertex[p]];
  return out;
}

}  // namespace prt
