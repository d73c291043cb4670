// The exact "compression" (exact_form): a cluster per vertex whose mean is the
// vertex's transfer and no components, so nothing is lost.
#include <array>
#include <numeric>

#include "prt/compressor.hpp"
#include "prt/plugin.hpp"
#include "prt/row_gather.hpp"

namespace prt {

class NoCompression final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "keeps the transfer exact (no compression)";
  static constexpr auto parameters() { return std::array<ParamSpecRecord, 0>{}; }

  explicit NoCompression(const Params&) {}

  bool exact() const override { return true; }

  // Its own exact form, or a basis's sparse approximation that replaced it.
  void check_encoding(const CompressedTransfer& c) const override {
    if (!c.sparse() && (c.components != 0 || c.clusters() != c.vertices()))
      throw Error("the encoding has " + std::to_string(c.clusters()) + " clusters and " +
                  std::to_string(c.components) +
                  " components; an exact form has a cluster per vertex and none");
  }

  CompressedTransfer encode(const TransferSignal& signal, const Mesh*) const override {
    CompressedTransfer c = exact_form(signal);
    c.compressor = "none";
    return c;
  }

  std::string why_not_distributed() const override { return ""; }

  // Each part's exact form of its rows; the first part's gathers every
  // part's rows as its means (a cluster per vertex of the whole mesh).
  CompressedTransfer encode_shard(const TransferSignal& local, const Mesh* mesh,
                                  const Distribution& where) const override {
    CompressedTransfer c = encode(local, mesh);
    if (!where.distributed()) return c;
    const RowParts& parts = *where.parts;
    MatrixXfRow whole = gather_float_rows(parts, c.means, "compressor \"none\"");
    if (!parts.first()) return c;  // its own rows, as the error measure reads them
    const Eigen::Index total = whole.rows(), n = c.dimension;
    c.means = std::move(whole);
    c.cluster_of_vertex.resize(std::size_t(total));
    std::iota(c.cluster_of_vertex.begin(), c.cluster_of_vertex.end(), 0);
    c.weights = MatrixXfRow(total, 0);
    c.representatives.assign(std::size_t(total), MatrixXfRow(0, n));
    return c;
  }
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::NoCompression, "none")
