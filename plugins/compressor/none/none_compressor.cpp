// The exact "compression": one cluster, zero mean, identity representatives,
// so the per-vertex weights are the transfer itself.
#include <array>

#include "prt/compressor.hpp"
#include "prt/plugin.hpp"

namespace prt {

class NoCompression final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "keeps the transfer exact (no compression)";
  static constexpr auto parameters() { return std::array<ParamSpecRecord, 0>{}; }

  explicit NoCompression(const Params&) {}

  CompressedTransfer encode(const TransferSignal& signal, const Mesh*) const override {
    CompressedTransfer c;
    c.compressor = "none";
    c.dimension = signal.dimension();
    c.components = static_cast<int>(signal.dimension());
    c.cluster_of_vertex.assign(signal.vertices(), 0);
    c.weights = signal.coefficients;
    c.means = MatrixXfRow::Zero(1, c.dimension);
    c.representatives.push_back(MatrixXfRow::Identity(c.dimension, c.dimension));
    return c;
  }
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::NoCompression, "none")
