// Principal component analysis: one cluster, n' components.
#include <array>
#include <numeric>

#include "../common/cluster_params.hpp"

namespace prt {

class PrincipalComponents final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "PCA: one cluster, n' principal components";
  static constexpr auto kComponents =
      param::integer("components", "8", 0, 1 << 20, "n', components kept");
  static constexpr auto parameters() { return param::records(kComponents); }

  explicit PrincipalComponents(const Params& params)
      : params_(params), components_(static_cast<int>(kComponents(params))) {}

  CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const override {
    return encode_shard(signal, mesh, Distribution::whole_signal(signal.vertices()));
  }

  bool reads_rows_from_file() const override { return true; }

  std::string why_not_distributed() const override { return ""; }

  void check_encoding(const CompressedTransfer& c) const override {
    if (c.clusters() != 1)
      throw Error("a PCA encoding has 1 cluster, not " + std::to_string(c.clusters()));
    compressor_params::check_budget(c, nullptr, 1, &kComponents, components_);
  }

  CompressedTransfer encode_shard(const TransferSignal& signal, const Mesh*,
                                  const Distribution& where) const override {
    compressor_params::require_finite(signal);
    const clustering::Rows rows = compressor_params::rows_of(signal, where);
    const int c = static_cast<int>(std::min<Eigen::Index>(components_, signal.dimension()));
    const std::vector<std::int32_t> labels(std::size_t(signal.vertices()), 0);
    CompressedTransfer compressed =
        clustering::assemble(rows, labels, clustering::fit_models(rows, labels, 1, {c}), "pca");
    if (rows.parts->first()) compressor_params::report_budget_used("pca", params_, compressed);
    clustering::gather_rows(rows, compressed);
    return compressed;
  }

 private:
  Params params_;  // for the located warning when the budget exceeds the data
  int components_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::PrincipalComponents, "pca")
