// Clustered PCA (Sloan et al. 2003): static, iterative or adaptive, with the
// optional cluster-coherence passes of §5.
#include "../common/cluster_params.hpp"

namespace prt {

class ClusteredPca final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "clustered PCA: static, iterative or adaptive (Sloan 2003 §4), overdraw reduction (§5)";
  static constexpr auto parameters() {
    using namespace schema;
    return compressor_params::join(
        compressor_params::clustering(),
        std::array{
            choice("method", "static", "static|iterative|adaptive", "CPCA variant"),
            integer("components", "8", 0, 1 << 20, "n' per cluster (adaptive: on average)"),
            integer("iterations_per_component", "10", 1, 1000,
                    "iterative/adaptive: classification passes per added component"),
            integer("adaptive_iterations", "5", 1, 1000, "adaptive: redistribution passes")});
  }

  explicit ClusteredPca(const Params& params) : params_(params) {}

  CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const override {
    compressor_params::require_finite(signal);
    clustering::CpcaOptions options;
    options.lbg = compressor_params::lbg_options(params_, mesh);
    const std::string method = params_.get_string("method");
    options.method = method == "iterative"  ? clustering::Method::iterative
                     : method == "adaptive" ? clustering::Method::adaptive
                                            : clustering::Method::static_pca;
    options.components = static_cast<int>(params_.get_int("components"));
    options.iterations_per_component =
        static_cast<int>(params_.get_int("iterations_per_component"));
    options.adaptive_iterations = static_cast<int>(params_.get_int("adaptive_iterations"));
    const auto result = clustering::cpca(signal.coefficients, options);
    return compressor_params::finish("cpca", params_, signal.coefficients, result.labels,
                                     result.models, mesh);
  }

 private:
  Params params_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::ClusteredPca, "cpca")
