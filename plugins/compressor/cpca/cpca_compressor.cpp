// Clustered PCA (Sloan et al. 2003): static, iterative or adaptive, with the
// optional cluster-coherence passes of §5.
#include "../common/cluster_params.hpp"

namespace prt {

class ClusteredPca final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "clustered PCA: static, iterative or adaptive (Sloan 2003 §4), overdraw reduction (§5)";
  static constexpr auto kMethod =
      param::choice<clustering::Method>("method", "static",
                                        {{"static", clustering::Method::static_pca},
                                         {"iterative", clustering::Method::iterative},
                                         {"adaptive", clustering::Method::adaptive}},
                                        "CPCA variant");
  static constexpr auto kComponents =
      param::integer("components", "8", 0, 1 << 20, "n' per cluster (adaptive: on average)");
  static constexpr auto kIterationsPerComponent =
      param::integer("iterations_per_component", "10", 1, 1000,
                     "iterative/adaptive: classification passes per added component");
  static constexpr auto kAdaptiveIterations =
      param::integer("adaptive_iterations", "5", 1, 1000, "adaptive: redistribution passes");
  static constexpr auto parameters() {
    return compressor_params::join(
        compressor_params::clustering(),
        param::records(kMethod, kComponents, kIterationsPerComponent, kAdaptiveIterations));
  }

  // Every parameter is read here, so a bad one is refused before any ray.
  explicit ClusteredPca(const Params& params)
      : params_(params), coherence_(compressor_params::coherence_options(params)) {
    options_.lbg = compressor_params::lbg_options(params);
    options_.method = kMethod(params);
    options_.components = static_cast<int>(kComponents(params));
    options_.iterations_per_component = static_cast<int>(kIterationsPerComponent(params));
    options_.adaptive_iterations = static_cast<int>(kAdaptiveIterations(params));
  }

  CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const override {
    return encode_shard(signal, mesh, Distribution::whole_signal(signal.vertices()));
  }

  bool reads_rows_from_file() const override { return true; }

  std::string why_not_distributed() const override {
    return compressor_params::why_not_distributed(coherence_, options_.lbg);
  }

  // Adaptive CPCA spends `components` per cluster on average, so only its
  // clusters are bounded.
  void check_encoding(const CompressedTransfer& c) const override {
    const bool adaptive = options_.method == clustering::Method::adaptive;
    compressor_params::check_budget(c, &compressor_params::kClusters, options_.lbg.clusters,
                                    adaptive ? nullptr : &kComponents, options_.components);
  }

  CompressedTransfer encode_shard(const TransferSignal& signal, const Mesh* mesh,
                                  const Distribution& where) const override {
    compressor_params::require_finite(signal);
    clustering::CpcaOptions options = options_;
    options.lbg = compressor_params::kept_in(
        compressor_params::with_mesh(options_.lbg, params_, mesh), where);
    const clustering::Rows rows = compressor_params::rows_of(signal, where);
    const auto result = clustering::cpca(rows, options);
    return compressor_params::finish("cpca", coherence_, params_, rows, result.labels,
                                     result.models, mesh);
  }

 private:
  Params params_;  // for located errors at encode time (a missing mesh)
  compressor_params::CoherenceOptions coherence_;
  clustering::CpcaOptions options_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::ClusteredPca, "cpca")
