// Per-vertex transfer and its compressed form: the values passed from the bake
// stage to compression and on to rendering.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace prt {

using MatrixXfRow = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Rows kept out of memory (a transfer larger than the bake's memory budget):
// what a signal needs of them. The run's RowFile (prt/row_file.hpp), a
// mapped file, is one; the signal does not know which.
class OutOfCoreRows {
 public:
  virtual ~OutOfCoreRows() = default;
  virtual Eigen::Index rows() const = 0;
  virtual Eigen::Index cols() const = 0;
  virtual Eigen::Map<const MatrixXfRow> matrix() const = 0;
  // Lets the resident pages of rows [first, last) go.
  virtual void release(Eigen::Index first, Eigen::Index last) const = 0;
  void release_all() const { release(0, rows()); }
  // The folder that holds them: where a derived signal's rows may go too.
  virtual const std::filesystem::path& folder() const = 0;
};

// v x n transfer, one row per vertex. For diffuse transfer n is the basis size
// and the exit radiance is row . light (per colour channel of the light). For
// glossy transfer each row is the N_r x N_i matrix M_p, row-major, mapping the
// light vector to exit-radiance coefficients in the scene's exit basis. The
// material's RGB albedo multiplies the result. Colour materials whose
// channels need different transfers stack one block per distinct channel
// material in each row (channel_groups blocks of exit_rows x N_i); colour
// channel c reads block group_of_channel[c].
struct TransferSignal {
  MatrixXfRow coefficients;
  std::string kind = "diffuse";  // "diffuse" (vectors) or "glossy" (matrices)
  int exit_rows = 1;             // N_r: 1 for diffuse transfer
  int channel_groups = 1;
  std::array<int, 3> group_of_channel{0, 0, 0};
  // Out of core (a transfer larger than the bake's memory budget): the rows
  // are there (a mapped file) and `coefficients` is empty. Readers that accept
  // it (Compressor::reads_rows_from_file) read rows() and release() what
  // they are done with; load() brings the rows into memory for the others.
  std::shared_ptr<const OutOfCoreRows> file;

  bool glossy() const { return kind == "glossy"; }
  bool on_disk() const { return file != nullptr; }
  Eigen::Index vertices() const;
  Eigen::Index dimension() const;
  // The rows, wherever they are.
  Eigen::Map<const MatrixXfRow> rows() const;
  // Lets the pages of rows [first, last) go (no-op in memory).
  void release(Eigen::Index first, Eigen::Index last) const;
  // The same signal with its rows in memory (a copy of the file's rows).
  TransferSignal loaded() const;
};

// One form for every compressor: per vertex a cluster index and n'_k weights;
// per cluster a mean and n'_k representative vectors; optional supercluster
// ids. VQ is n' = 0, PCA is one cluster, "none" (exact_form) is a cluster per
// vertex whose mean is the vertex's signal, with no components. Adaptive
// CPCA gives clusters different n'_k; weights are stored padded to the largest.
struct CompressedTransfer {
  std::string compressor;
  Eigen::Index dimension = 0;                         // n
  int components = 0;                                 // max_k n'_k: columns of `weights`
  std::vector<std::int32_t> cluster_of_vertex;        // v
  MatrixXfRow weights;                                // v x components (zero past n'_k)
  MatrixXfRow means;                                  // clusters x n
  std::vector<MatrixXfRow> representatives;           // per cluster: n'_k x n
  std::vector<std::int32_t> supercluster_of_cluster;  // empty, or one id per cluster
  // Sparse form (non-linear approximation, e.g. Haar keeping the k largest
  // coefficients): when non-empty, v x components indices into the n basis
  // coefficients, and t_p = mean_0 + sum_j weights(p, j) e_{index(p, j)}.
  std::vector<std::int32_t> weight_index;
  bool sparse() const { return !weight_index.empty(); }
  // Figures a compressor reports about its own run (e.g. overdraw before the
  // coherence passes); they end up in the encode report and the bake metrics.
  std::map<std::string, double> statistics;

  int components_of(Eigen::Index cluster) const {
    return static_cast<int>(representatives[cluster].rows());
  }

  Eigen::Index vertices() const { return static_cast<Eigen::Index>(cluster_of_vertex.size()); }
  Eigen::Index clusters() const { return means.rows(); }

  // Reconstructs the v x n signal (for error measurement).
  MatrixXfRow decode() const;
  // Reconstructs vertex p's row into `out` (n floats).
  void decode_row(Eigen::Index p, Eigen::Ref<Eigen::RowVectorXf> out) const;
  // Throws prt::Error unless the sizes and cluster indices agree with each
  // other and with `vertex_count`.
  // `finite`: also refuse NaN and infinite values (an exact form of a
  // signal that holds them keeps them).
  void validate(Eigen::Index vertex_count, bool finite = true) const;
  // Floats stored: sum_p n'_k(p) + sum_k (n'_k + 1) n  (= m_p n' + m_c (n' + 1) n
  // when every cluster has n' components).
  double stored_floats() const;
};

// The uncompressed transfer in the one compressed form: a cluster per vertex
// whose mean is the vertex's transfer, no components (v x n floats, exact).
CompressedTransfer exact_form(const TransferSignal& signal);

// Non-linear approximation: keeps the `terms` largest-magnitude coefficients of
// each vertex, stored sparsely (index + value).
CompressedTransfer keep_largest(const TransferSignal& signal, int terms);

// Squared error sum over vertices of |t_p - reconstruction_p|^2.
double squared_error(const MatrixXfRow& exact, const MatrixXfRow& approximation);

// A signal of the same shape and kind whose rows are map(rows [begin, end) of
// `signal`), block by block (in parallel), kept where `signal`'s are: in
// memory, or in a new file beside its rows
// (a RowFile: framework/src/map_row_blocks.cpp). Each block of `signal` is
// released once read, so an out-of-core signal is read in one pass.
using RowBlockMap = std::function<MatrixXfRow(Eigen::Ref<const MatrixXfRow> rows)>;
TransferSignal map_row_blocks(const TransferSignal& signal, Eigen::Index block_rows,
                              const RowBlockMap& map);

}  // namespace prt
