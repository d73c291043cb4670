// Principal component analysis: one cluster, n' components.
#include <array>
#include <numeric>

#include "../common/cluster_params.hpp"

namespace prt {

class PrincipalComponents final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "PCA: one cluster, n' principal components";
  static constexpr auto parameters() {
    return std::array{schema::integer("components", "8", 0, 1 << 20, "n', components kept")};
  }

  explicit PrincipalComponents(const Params& params)
      : components_(static_cast<int>(params.get_int("components"))) {}

  CompressedTransfer encode(const TransferSignal& signal, const Mesh*) const override {
    compressor_params::require_finite(signal);
    std::vector<std::uint32_t> all(signal.vertices());
    std::iota(all.begin(), all.end(), 0u);
    const int c = static_cast<int>(std::min<Eigen::Index>(components_, signal.dimension()));
    const std::vector<clustering::ClusterModel> model{
        clustering::fit_cluster(signal.coefficients, all, c)};
    return clustering::assemble(signal.coefficients,
                                std::vector<std::int32_t>(signal.vertices(), 0), model, "pca");
  }

 private:
  int components_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::PrincipalComponents, "pca")
