// Eigentransport (Nowrouzezahrai et al.): the principal components of the
// sampled transport itself. With T (v x s) the cosine-weighted visibility on a
// cube-map lattice of solid angles w, the PCA runs on T' = T diag(sqrt(w))
// centred by its mean over vertices, by a randomized SVD streamed from the
// visibility bits (no dense v x s matrix). The eigentransports E (d x s,
// orthonormal rows) define basis functions b_i(w_k) = E_ik / sqrt(w_k),
// orthonormal under the lattice's quadrature. Coefficients of transport and
// light are then both plain projections (the mean-compensated coefficients of
// §4.3: T Bᵀ and L Bᵀ, no full-dimensional mean at run time), and shading is a
// d-term dot product.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <mutex>
#include <random>

#include "prt/basis.hpp"
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/transport.hpp"

namespace prt {

class Eigentransport final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "eigentransport: PCA basis of the sampled transport (fit to the scene's rays)";
  static constexpr auto parameters() {
    using namespace schema;
    return std::array{
        integer("d", "48", 1, 4096,
                "basis functions: the mean direction and d - 1 eigentransports (the most, when "
                "variance is set)"),
        real("variance", "0", 0, 1,
             "if > 0: the fewest eigentransports capturing this fraction of the variance"),
        integer("oversampling", "10", 0, 1000, "randomized SVD: extra columns"),
        integer("power_iterations", "2", 0, 20, "randomized SVD: power iterations"),
        integer("seed", "1", 0, 9.2e18, "randomized SVD: seed")};
  }

  explicit Eigentransport(const Params& params)
      : max_d_(static_cast<int>(params.get_int("d"))),
        variance_(params.get_real("variance")),
        oversampling_(static_cast<int>(params.get_int("oversampling"))),
        power_iterations_(static_cast<int>(params.get_int("power_iterations"))),
        seed_(static_cast<std::uint64_t>(params.get_int("seed"))) {}

  int size() const override { return fitted() ? static_cast<int>(eigen_.rows()) : max_d_; }
  bool orthonormal() const override { return true; }
  bool can_fit() const override { return true; }

  Eigen::MatrixXd evaluate(const Directions& directions) const override {
    require_fitted();
    Eigen::MatrixXd values(directions.rows(), eigen_.rows());
    for (Eigen::Index k = 0; k < directions.rows(); ++k) {
      const int t = cubemap_texel(directions.row(k).transpose(), resolution_);
      values.row(k) = eigen_.col(t).transpose() / root_weights_[t];
    }
    return values;
  }

  std::optional<DirectionSet> native_directions() const override {
    if (!fitted()) return std::nullopt;
    return DirectionSet::cubemap(resolution_);
  }

  // Asked by the bake plan before any ray, and again when fitting.
  void check_directions(const DirectionSet& set) const override {
    const auto s = set.size();
    const int r = static_cast<int>(std::lround(std::sqrt(s / 6.0)));
    if (set.kind != "cubemap" || 6 * r * r != s)
      throw Error(
          "basis \"eigen\": fitting needs a cube-map direction set ([transport] "
          "directions = \"cubemap\"), got " +
          set.kind);
  }

  void fit(const FitData& data) override {
    const DirectionSet& set = *data.directions;
    const Mesh& mesh = *data.mesh;
    check_directions(set);
    const auto s = set.size();
    const int r = static_cast<int>(std::lround(std::sqrt(s / 6.0)));
    resolution_ = r;
    root_weights_ = set.weights.cwiseSqrt();
    const Eigen::Index v = static_cast<Eigen::Index>(mesh.vertex_count());
    const Eigen::Index columns = std::min<Eigen::Index>({max_d_ + oversampling_, s, v});

    // Streamed passes over vertex blocks of C = T diag(sqrt(w)) - 1 mean.
    // Blocks of 64 rows (3 MB at 6,144 directions) stay in cache between
    // building them and multiplying. Sums over vertices go through a fixed
    // number of chunks, each summed in vertex order and then added in chunk
    // order: a seed gives the same basis whatever the number of cores.
    constexpr std::size_t kRows = 64, kChunks = 16;
    const std::size_t vertices = mesh.vertex_count();
    auto block_rows = [&](std::size_t begin, std::size_t end, Eigen::MatrixXd& rows) {
      transport_rows(mesh, set, *data.visibility, begin, end, rows);
      rows *= root_weights_.asDiagonal();
      if (mean_.size()) rows.rowwise() -= mean_;
    };
    // visit(begin, rows, chunk) for every block, blocks of a chunk in order.
    auto for_blocks = [&](const auto& visit) {
      tbb::parallel_for(std::size_t(0), kChunks, [&](std::size_t chunk) {
        const std::size_t first = vertices * chunk / kChunks,
                          last = vertices * (chunk + 1) / kChunks;
        Eigen::MatrixXd rows;
        for (std::size_t begin = first; begin < last; begin += kRows) {
          block_rows(begin, std::min(last, begin + kRows), rows);
          visit(begin, rows, chunk);
        }
      });
    };
    mean_.resize(0);
    std::vector<Eigen::RowVectorXd> sums(kChunks, Eigen::RowVectorXd::Zero(s));
    for_blocks([&](std::size_t, const Eigen::MatrixXd& rows, std::size_t chunk) {
      sums[chunk] += rows.colwise().sum();
    });
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(s);
    for (const auto& part : sums) sum += part;
    mean_ = sum / double(v);

    std::mt19937_64 rng(seed_);
    std::normal_distribution<double> gaussian;
    Eigen::MatrixXd omega(s, columns);
    for (auto& x : omega.reshaped()) x = gaussian(rng);
    // Y = C Omega; Q = orth(Y); then power iterations Q <- orth(C orth(C^T Q)).
    auto times_c = [&](const Eigen::MatrixXd& right) {  // C * right: v x columns
      Eigen::MatrixXd out(v, right.cols());
      for_blocks([&](std::size_t begin, const Eigen::MatrixXd& rows, std::size_t) {
        out.middleRows(begin, rows.rows()).noalias() = rows * right;
      });
      return out;
    };
    auto c_transpose_times = [&](const Eigen::MatrixXd& left, double* energy) {  // C^T left
      std::vector<Eigen::MatrixXd> parts(kChunks, Eigen::MatrixXd::Zero(s, left.cols()));
      std::vector<double> energies(kChunks, 0.0);
      for_blocks([&](std::size_t begin, const Eigen::MatrixXd& rows, std::size_t chunk) {
        parts[chunk].noalias() += rows.transpose() * left.middleRows(begin, rows.rows());
        energies[chunk] += rows.squaredNorm();
      });
      Eigen::MatrixXd out = parts[0];
      double total = energies[0];
      for (std::size_t c = 1; c < kChunks; ++c) out += parts[c], total += energies[c];
      if (energy) *energy = total;
      return out;
    };
    auto orth = [](const Eigen::MatrixXd& m) {
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(m);
      return Eigen::MatrixXd(qr.householderQ() * Eigen::MatrixXd::Identity(m.rows(), m.cols()));
    };
    Eigen::MatrixXd q = orth(times_c(omega));
    for (int i = 0; i < power_iterations_; ++i)
      q = orth(times_c(orth(c_transpose_times(q, nullptr))));
    double total_energy = 0;
    const Eigen::MatrixXd small = c_transpose_times(q, &total_energy).transpose();  // Q^T C
    Eigen::BDCSVD<Eigen::MatrixXd> svd(small, Eigen::ComputeThinV);
    const Eigen::VectorXd sigma = svd.singularValues();
    int d = static_cast<int>(std::min<Eigen::Index>(max_d_, sigma.size()));
    if (variance_ > 0) {
      double captured = 0;
      for (int i = 0; i < sigma.size(); ++i) {
        captured += sigma[i] * sigma[i];
        if (captured >= variance_ * total_energy || i + 2 >= d) {
          d = std::min(d, i + 2);  // i + 1 eigentransports and the mean direction
          break;
        }
      }
    }
    // The first function is the mean transport's part outside the span of the
    // other d - 1: with it, projecting the uncentred transport reproduces the
    // PCA reconstruction mean + (T - mean) B^T B exactly, and the coefficients
    // are the mean-compensated ones of §4.3 (d in all, no s-dimensional mean).
    const int components = std::max(1, d - 1);
    const Eigen::MatrixXd pcs = svd.matrixV().leftCols(components).transpose();
    Eigen::RowVectorXd outside = mean_ - (mean_ * pcs.transpose()) * pcs;
    const bool with_mean = d > 1 && outside.norm() > 1e-12 * std::max(1.0, mean_.norm());
    eigen_.resize(with_mean ? d : components, s);
    if (with_mean) {
      eigen_.row(0) = outside / outside.norm();
      eigen_.bottomRows(components) = pcs;
    } else {
      eigen_ = pcs;
    }
    captured_variance_ = sigma.head(components).squaredNorm() / std::max(total_energy, 1e-300);
  }

  BasisState save() const override {
    require_fitted();
    BasisState state;
    state.matrices["eigentransports"] = eigen_;
    state.matrices["mean"] = mean_;
    state.matrices["root_weights"] = root_weights_.transpose();
    state.matrices["resolution"] = Eigen::MatrixXd::Constant(1, 1, resolution_);
    state.matrices["captured_variance"] = Eigen::MatrixXd::Constant(1, 1, captured_variance_);
    return state;
  }

  void load(const BasisState& state) override {
    auto get = [&](const char* name) -> const Eigen::MatrixXd& {
      auto it = state.matrices.find(name);
      if (it == state.matrices.end())
        throw Error(std::string("basis \"eigen\": saved state lacks \"") + name + "\"");
      return it->second;
    };
    eigen_ = get("eigentransports");
    mean_ = get("mean");
    root_weights_ = get("root_weights").transpose();
    resolution_ = static_cast<int>(get("resolution")(0, 0));
    captured_variance_ = get("captured_variance")(0, 0);
    if (eigen_.cols() != 6 * resolution_ * resolution_ || root_weights_.size() != eigen_.cols())
      throw Error("basis \"eigen\": saved state has inconsistent sizes");
  }

 private:
  bool fitted() const { return eigen_.size() > 0; }
  void require_fitted() const {
    if (!fitted())
      throw Error("basis \"eigen\" is not fitted yet: it is fitted to a scene's rays by the bake");
  }

  int max_d_;
  double variance_;
  int oversampling_, power_iterations_;
  std::uint64_t seed_;
  int resolution_ = 0;
  Eigen::MatrixXd eigen_;  // d x s
  Eigen::RowVectorXd mean_;
  Eigen::VectorXd root_weights_;
  double captured_variance_ = 0;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::Eigentransport, "eigen")
