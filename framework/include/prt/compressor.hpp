// The compressor interface: TransferSignal -> CompressedTransfer.
#pragma once
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Compressor : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::compressor;
  // `mesh` (may be null) gives compressors that care the triangles, for
  // overdraw reduction and geometry-coherent clustering.
  virtual CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const = 0;
  // Capability: the encoding reproduces the signal exactly (no compression),
  // so it may be replaced by a basis's own sparse approximation and needs no
  // comparison against the exact transfer.
  virtual bool exact() const { return false; }
};

// What every encode reports (DESIGN §3): squared error, its per-vertex
// distribution, storage and overdraw.
struct CompressionReport {
  double squared_error = 0;  // SE = sum_p |t_p - t~_p|^2
  double vertex_error_p50 = 0, vertex_error_p90 = 0, vertex_error_p99 = 0, vertex_error_max = 0;
  double stored_floats = 0;  // sum_p n'_k(p) + sum_k (n'_k + 1) n
  double stored_bytes = 0;   // as float32
  double encode_seconds = 0;
  double overdraw = 0;               // average distinct clusters per triangle (0 without a mesh)
  double supercluster_overdraw = 0;  // the same over superclusters (= overdraw without them)
  std::size_t clusters = 0;
  std::map<std::string, double> statistics;  // the compressor's own figures

  std::string json() const;
  std::string text() const;
};

// Average number of distinct cluster ids among each triangle's vertices: how
// many times a triangle is drawn when each cluster is drawn in its own pass.
double average_overdraw(const Mesh& mesh, const std::vector<std::int32_t>& id_of_vertex);

// Cluster ids mapped through superclusters (identity when there are none).
std::vector<std::int32_t> supercluster_of_vertex(const CompressedTransfer& compressed);

CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                          const Mesh* mesh, double encode_seconds);

}  // namespace prt
