// Vector quantisation: LBG clusters, each vertex stored as its cluster's mean
// (n' = 0).
#include "../common/cluster_params.hpp"

namespace prt {

class VectorQuantizer final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "vector quantisation by LBG (hyper-box or k-means++ start, null-cluster splitting)";
  static constexpr auto parameters() { return compressor_params::clustering(); }

  explicit VectorQuantizer(const Params& params)
      : params_(params),
        coherence_(compressor_params::coherence_options(params)),
        lbg_(compressor_params::lbg_options(params)) {}

  CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const override {
    return encode_shard(signal, mesh, Distribution::whole_signal(signal.vertices()));
  }

  bool reads_rows_from_file() const override { return true; }

  std::string why_not_distributed() const override {
    return compressor_params::why_not_distributed(coherence_, lbg_);
  }

  void check_encoding(const CompressedTransfer& c) const override {
    if (c.components != 0)
      throw Error("a VQ encoding has no components, not " + std::to_string(c.components));
    compressor_params::check_budget(c, &compressor_params::kClusters, lbg_.clusters, nullptr, 0);
  }

  CompressedTransfer encode_shard(const TransferSignal& signal, const Mesh* mesh,
                                  const Distribution& where) const override {
    compressor_params::require_finite(signal);
    const clustering::Rows rows = compressor_params::rows_of(signal, where);
    const auto clusters = clustering::lbg(
        rows, compressor_params::kept_in(compressor_params::with_mesh(lbg_, params_, mesh), where));
    std::vector<clustering::ClusterModel> models(clusters.means.rows());
    for (std::size_t k = 0; k < models.size(); ++k)
      models[k] = {clusters.means.row(k), clustering::RowMatrixXd(0, clusters.means.cols()), {}};
    return compressor_params::finish("vq", coherence_, params_, rows, clusters.labels, models,
                                     mesh);
  }

 private:
  Params params_;
  compressor_params::CoherenceOptions coherence_;
  clustering::LbgOptions lbg_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::VectorQuantizer, "vq")
