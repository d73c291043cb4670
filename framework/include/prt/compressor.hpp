// The compressor interface: TransferSignal -> CompressedTransfer.
#pragma once
#include <optional>

#include "prt/error.hpp"
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/row_parts.hpp"
#include "prt/transfer.hpp"

namespace prt {

class RenderedMetric;
class PartKeeper;  // prt/part_keeper.hpp

// Where a distributed compressor's rows sit (prt-mpi): the signal it is given
// holds rows parts->shard() of the whole; sums over rows go through the parts
// (prt/row_parts.hpp), so the result equals one process's.
struct Distribution {
  std::shared_ptr<const RowParts> parts;  // null: one process, every row
  // Where a long encode keeps its state, at most every checkpoint_seconds,
  // and finds it again when the bake is rerun after a kill (the bake's
  // checkpoint folder; a distributed run's parts share it, so a distributed
  // encode keeps parts named by its shard, decides when to keep on one part
  // for all, and resumes on every part or none). Null: nothing is kept.
  const PartKeeper* checkpoint = nullptr;
  double checkpoint_seconds = 60;

  bool distributed() const { return parts && parts->distributed(); }
  // The parts, or a single part holding all `rows` rows by default.
  std::shared_ptr<const RowParts> row_parts(Eigen::Index rows) const {
    return parts ? parts : single_part(rows);
  }
  static Distribution whole_signal(Eigen::Index rows) { return {single_part(rows)}; }
};

class Compressor : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::compressor;
  // `mesh` (may be null) gives compressors that care the triangles, for
  // overdraw reduction and geometry-coherent clustering.
  virtual CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const = 0;
  // Capability: encode_shard runs on shards of the signal across parts. An
  // empty answer means yes; otherwise it says why not (e.g. a parameter that
  // needs every vertex in one process).
  virtual std::string why_not_distributed() const { return "does not run distributed"; }
  // Encodes this part's rows; the first part returns the whole compressed
  // form, the others their rows of it. One part: encode().
  virtual CompressedTransfer encode_shard(const TransferSignal& local, const Mesh* mesh,
                                          const Distribution& where) const {
    if (!where.distributed()) return encode(local, mesh);
    throw Error("this compressor " + why_not_distributed());
  }
  // Capability: encode reads the rows through signal.rows() and releases
  // them as it goes, so it takes a signal whose rows are in a mapped file
  // (TransferSignal::on_disk, a bake larger than its memory budget). Others
  // are given the rows loaded into memory.
  virtual bool reads_rows_from_file() const { return false; }
  // Capability: the encoding reproduces the signal exactly (no compression),
  // so it may be replaced by a basis's own sparse approximation and needs no
  // comparison against the exact transfer.
  virtual bool exact() const { return false; }
  // Checks an encoding read from a bake file against this compressor as its
  // record configures it: throws prt::Error naming what it could not have
  // made (more clusters or components than its budget, another form).
  // Default: no check beyond the form's own (CompressedTransfer::validate).
  virtual void check_encoding(const CompressedTransfer& encoding) const { (void)encoding; }
};

// What every encode reports (DESIGN §3): squared error, its per-vertex
// distribution, storage and overdraw.
struct CompressionReport {
  double squared_error = 0;  // SE = sum_p |t_p - t~_p|^2
  // SE measured in the rendered metric (a basis that is not orthonormal):
  // sum_p |F(t_p - t~_p)|^2, the function-space error of what is rendered.
  bool rendered_metric = false;
  double vertex_error_p50 = 0, vertex_error_p90 = 0, vertex_error_p99 = 0, vertex_error_max = 0;
  double stored_floats = 0;  // sum_p n'_k(p) + sum_k (n'_k + 1) n
  double stored_bytes = 0;   // as float32
  // What a renderer needs besides the floats: a 32-bit cluster id per vertex
  // when there is more than one cluster, and the supercluster map.
  double index_bytes = 0;
  double total_bytes() const { return stored_bytes + index_bytes; }
  // sum_p |t_p|^2 in the same metric as SE: SE relative to it is comparable
  // across scenes, bases and lights.
  double signal_energy = 0;
  double relative_squared_error() const {
    return signal_energy > 0 ? squared_error / signal_energy : 0.0;
  }
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

// The signal as `compressor` reads it: `signal` itself, or, for a
// compressor that reads rows from memory only, the rows of an on-disk
// signal loaded into `loaded` (with a warning that names `name`).
const TransferSignal& readable_signal(const Compressor& compressor, const std::string& name,
                                      const TransferSignal& signal,
                                      std::optional<TransferSignal>& loaded);

// The report of an encode. Distributed: `signal` holds this rank's rows and
// `compressed` is encode_shard's result; the squared error is on every rank,
// the rest on rank 0. With a metric the errors are measured in it (the
// function-space error of what is rendered, prt/rendered_metric.hpp).
CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                          const Mesh* mesh, double encode_seconds, const Distribution& where,
                          const RenderedMetric* metric = nullptr);
inline CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                                 const Mesh* mesh, double encode_seconds) {
  return measure(signal, compressed, mesh, encode_seconds,
                 Distribution::whole_signal(signal.vertices()));
}

// |t_p - decoded_p|^2 for every row of `signal` (rows of `compressed` alike),
// in `metric` when given.
std::vector<double> vertex_errors(const TransferSignal& signal,
                                  const CompressedTransfer& compressed,
                                  const RenderedMetric* metric = nullptr);

// The ranks' rows of a compressed form (cluster ids, weights, sparse
// indices) joined in rank order on rank 0; other ranks keep theirs.
void gather_rows(const Distribution& where, CompressedTransfer& compressed);

}  // namespace prt
