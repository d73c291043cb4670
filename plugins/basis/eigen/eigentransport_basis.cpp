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
#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "prt/basis.hpp"
#include "prt/log.hpp"
#include "prt/mesh.hpp"
#include "prt/part_keeper.hpp"
#include "prt/plugin.hpp"
#include "prt/row_blocks.hpp"
#include "prt/row_parts.hpp"
#include "prt/transport.hpp"
#include "prt/visible_products.hpp"

namespace prt {

namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

void householder_columns(Eigen::MatrixXd& m) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(m);
  m = qr.householderQ() * Eigen::MatrixXd::Identity(m.rows(), m.cols());
}

constexpr Eigen::Index kBlock = 1024;  // fixed: the same bits on any number of cores

// m's columns made orthonormal, in place, for a matrix every rank holds
// whole (a row per direction). Tall matrices go by Cholesky QR twice: two
// Gram products and triangular solves in fixed row blocks on every core,
// where Householder QR ran on one core (0.17 s of the bunny's 2 s fit). Two
// passes are accurate while cond(m) < ~1e8; a worse-conditioned or
// rank-deficient m, and small ones, go by Householder.
bool cholesky_qr_pass(Eigen::MatrixXd& m, const Eigen::MatrixXd& gram, Eigen::Index first_row);

void orthonormalize(Eigen::MatrixXd& m) {
  if (m.rows() < 4 * kBlock) return householder_columns(m);
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Index blocks = (m.rows() + kBlock - 1) / kBlock;
    std::vector<Eigen::MatrixXd> parts(static_cast<std::size_t>(blocks));
    for_each_row_block(Eigen::Index(0), m.rows(), kBlock,
                       [&](Eigen::Index begin, Eigen::Index end) {
                         const auto rows = m.middleRows(begin, end - begin);
                         parts[static_cast<std::size_t>(begin / kBlock)] = rows.transpose() * rows;
                       });
    Eigen::MatrixXd gram = parts[0];
    for (std::size_t b = 1; b < parts.size(); ++b) gram += parts[b];
    if (!cholesky_qr_pass(m, gram, 0)) return householder_columns(m);
  }
}

// One pass of Cholesky QR with m's Gram matrix: m <- m U^-1, in fixed row
// blocks (rows counted from first_row of the whole matrix). False, m
// untouched, when the Gram is too ill-conditioned: the diagonal's spread
// bounds cond(m) from below only (by up to ~100x at tens of columns), and
// 1e-5 keeps cond well under ~1e8.
bool cholesky_qr_pass(Eigen::MatrixXd& m, const Eigen::MatrixXd& gram, Eigen::Index first_row) {
  const Eigen::LLT<Eigen::MatrixXd> llt(gram);
  const Eigen::VectorXd diagonal = llt.matrixL().toDenseMatrix().diagonal();
  if (llt.info() != Eigen::Success || !diagonal.allFinite() ||
      diagonal.minCoeff() <= 1e-5 * diagonal.maxCoeff())
    return false;
  // Each block is solved in a matrix of its own: Eigen's kernels may add in
  // an order that depends on where the rows lie in memory (a rank's shard
  // starts elsewhere than the whole matrix).
  for_each_row_block(first_row, first_row + m.rows(), kBlock,
                     [&](Eigen::Index begin, Eigen::Index end) {
                       Eigen::MatrixXd rows = m.middleRows(begin - first_row, end - begin);
                       llt.matrixU().solveInPlace<Eigen::OnTheRight>(rows);
                       m.middleRows(begin - first_row, end - begin) = rows;
                     });
  return true;
}

// The same for a matrix with a row per vertex, each rank holding its
// shard's rows: the Gram matrices are sums over segments (RowParts::sum),
// and a small or ill-conditioned matrix is gathered whole to every rank for
// Householder QR, so that every rank, and a single process, get the same
// bits.
void orthonormalize_rows(Eigen::MatrixXd& m, const RowParts& parts) {
  const Shard shard = parts.shard();
  const Eigen::Index cols = m.cols();
  auto householder_gathered = [&] {
    if (!parts.distributed()) return householder_columns(m);
    std::vector<double> mine(std::size_t(m.rows() * cols));
    Eigen::Map<RowMajor>(mine.data(), m.rows(), cols) = m;
    Eigen::MatrixXd whole_matrix(shard.total, cols);
    Eigen::Index at = 0;
    for (const auto& part : parts.allgather(mine)) {
      const Eigen::Index rows = Eigen::Index(part.size()) / std::max<Eigen::Index>(1, cols);
      whole_matrix.middleRows(at, rows) = Eigen::Map<const RowMajor>(part.data(), rows, cols);
      at += rows;
    }
    householder_columns(whole_matrix);
    m = whole_matrix.middleRows(shard.first, shard.rows());
  };
  if (shard.total < 4 * kBlock) return householder_gathered();
  for (int pass = 0; pass < 2; ++pass) {
    const auto partial = [&](Eigen::Index segment) {
      const Eigen::Index begin = segment_begin(segment) - shard.first,
                         end = segment_end(segment, shard.total) - shard.first;
      Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(cols, cols);
      for (Eigen::Index b = begin; b < end; b += kBlock) {  // blocks in order, each copied
        const Eigen::MatrixXd rows = m.middleRows(b, std::min(kBlock, end - b));
        gram.noalias() += rows.transpose() * rows;
      }
      return std::vector<double>(gram.data(), gram.data() + gram.size());
    };
    const std::vector<double> sum = parts.sum(partial);
    const Eigen::MatrixXd gram = Eigen::Map<const Eigen::MatrixXd>(sum.data(), cols, cols);
    if (!cholesky_qr_pass(m, gram, shard.first)) return householder_gathered();
  }
}

// The column sums of a matrix with a row per vertex, over every rank's shard.
Eigen::RowVectorXd column_sums_of_rows(const Eigen::MatrixXd& m, const RowParts& parts) {
  const Shard shard = parts.shard();
  const auto partial = [&](Eigen::Index segment) {
    const Eigen::Index begin = segment_begin(segment) - shard.first,
                       end = segment_end(segment, shard.total) - shard.first;
    // Row by row: a vectorized column sum's order depends on the column's
    // alignment, which differs between a shard and the whole matrix.
    Eigen::RowVectorXd sums = Eigen::RowVectorXd::Zero(m.cols());
    for (Eigen::Index r = begin; r < end; ++r) sums += m.row(r);
    return std::vector<double>(sums.data(), sums.data() + sums.size());
  };
  const std::vector<double> sum = parts.sum(partial);
  if (sum.empty()) return Eigen::RowVectorXd::Zero(m.cols());
  return Eigen::Map<const Eigen::RowVectorXd>(sum.data(), m.cols());
}

// C = T W - 1 mean (W = diag(sqrt(w))) in products, never built:
// C X = T (W X) - 1 (mean X) and C^T Y = W T^T Y - mean^T (1^T Y), where the
// products with T visit only the visible (vertex, direction) pairs. The
// vertices x columns buffers are kept across passes (fresh pages are slow).
class CentredTransport {
 public:
  CentredTransport(const Mesh& mesh, const DirectionSet& set, const VisibilityBits& visibility,
                   const TransposedVisibility& transposed, const Eigen::VectorXd& root_weights,
                   const Eigen::RowVectorXd& mean, const RowParts& parts)
      : mesh_(mesh),
        set_(set),
        visibility_(visibility),
        transposed_(transposed),
        root_weights_(root_weights),
        mean_(mean),
        parts_(parts),
        shard_(parts.shard()) {}

  // q = C right: this shard's rows.
  void times(const Eigen::MatrixXd& right, Eigen::MatrixXd& q) {
    padded_right_.assign(root_weights_.asDiagonal() * right);
    visible_times(mesh_, set_, visibility_, padded_right_, padded_out_, std::size_t(shard_.first));
    const Eigen::RowVectorXd shift = mean_ * right;
    q = padded_out_.matrix_view();
    q.rowwise() -= shift;
  }
  // C^T left (s x columns), summed over the ranks.
  Eigen::MatrixXd transpose_times(const Eigen::MatrixXd& left) {
    padded_left_.assign(left);
    Eigen::MatrixXd product = root_weights_.asDiagonal() *
                              visible_transpose_sum(mesh_, set_, transposed_, padded_left_, parts_);
    product.noalias() -= mean_.transpose() * column_sums_of_rows(left, parts_);
    return product;
  }

 private:
  const Mesh& mesh_;
  const DirectionSet& set_;
  const VisibilityBits& visibility_;
  const TransposedVisibility& transposed_;
  const Eigen::VectorXd& root_weights_;
  const Eigen::RowVectorXd& mean_;
  const RowParts& parts_;
  const Shard shard_;
  PaddedRows padded_right_, padded_left_, padded_out_;
};

}  // namespace

class Eigentransport final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "eigentransport: PCA basis of the sampled transport (fit to the scene's rays)";
  static constexpr auto kD =
      param::integer("d", "48", 1, 4096,
                     "basis functions: the mean direction and d - 1 eigentransports (the most, "
                     "when variance is set)");
  static constexpr auto kVariance =
      param::real("variance", "0", 0, 1,
                  "if > 0: the fewest eigentransports capturing this fraction of the variance");
  static constexpr auto kOversampling =
      param::integer("oversampling", "10", 0, 1000, "randomized SVD: extra columns");
  static constexpr auto kPowerIterations =
      param::integer("power_iterations", "2", 0, 20, "randomized SVD: power iterations");
  static constexpr auto kSeed = param::integer("seed", "1", 0, 9.2e18, "randomized SVD: seed");
  static constexpr auto parameters() {
    return param::records(kD, kVariance, kOversampling, kPowerIterations, kSeed);
  }

  explicit Eigentransport(const Params& params)
      : max_d_(static_cast<int>(kD(params))),
        variance_(kVariance(params)),
        oversampling_(static_cast<int>(kOversampling(params))),
        power_iterations_(static_cast<int>(kPowerIterations(params))),
        seed_(static_cast<std::uint64_t>(kSeed(params))) {}

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

  bool can_fit_distributed() const override { return true; }

  void fit(const FitData& data) override {
    const DirectionSet& set = *data.directions;
    const Mesh& mesh = *data.mesh;
    check_directions(set);
    const auto s = set.size();
    const int r = static_cast<int>(std::lround(std::sqrt(s / 6.0)));
    resolution_ = r;
    root_weights_ = set.weights.cwiseSqrt();
    // This process's vertices (a rank's shard, or all), and every sum over
    // vertices through the run's parts: a seed gives the same basis, bit for
    // bit, whatever the number of cores or ranks.
    const auto parts = data.row_parts();
    const Shard shard = parts->shard();
    const VisibilityBits& visibility = *data.visibility;
    if (Eigen::Index(visibility.vertices()) != shard.rows() ||
        Eigen::Index(mesh.vertex_count()) != shard.total)
      throw Error("basis \"eigen\": visibility of " + std::to_string(visibility.vertices()) +
                  " vertices for a shard of " + std::to_string(shard.rows()) + " of a mesh of " +
                  std::to_string(mesh.vertex_count()));
    const Eigen::Index v = shard.total;
    const TransposedVisibility transposed(visibility);
    double transport_energy = 0;  // ||T W||_F^2
    mean_ = column_sums(mesh, set, transposed, *parts, transport_energy) / double(v);
    CentredTransport c(mesh, set, visibility, transposed, root_weights_, mean_, *parts);
    const Eigen::MatrixXd q =
        range_of(c, data, *parts, std::min<Eigen::Index>({max_d_ + oversampling_, s, v}));
    // ||C||_F^2 = ||T W||_F^2 - v ||mean||^2 (C's rows are centred). It loses
    // digits when the mean holds nearly all the energy (the error is ~eps
    // ||T W||^2); below 1e-12 ||T W||^2 the rows are the same up to rounding,
    // there is no variance, and the singular values are rounding noise.
    const double total_energy = transport_energy - double(v) * mean_.squaredNorm();
    const Eigen::MatrixXd small = c.transpose_times(q).transpose();  // Q^T C
    Eigen::BDCSVD<Eigen::MatrixXd> svd(small, Eigen::ComputeThinV);
    keep_functions(svd, total_energy, !(total_energy > 1e-12 * transport_energy));
  }

  // Randomized range finder: Y = C Omega, Q = orth(Y), then power iterations
  // Q <- orth(C orth(C^T Q)). A killed bake resumes after the last power
  // iteration it kept: Q is orth(C Z) of that iteration's Z (s x columns,
  // small; the same on every rank, so rank 0 keeps it), and the same bits
  // follow. Returns this shard's rows of Q.
  Eigen::MatrixXd range_of(CentredTransport& c, const FitData& data, const RowParts& parts,
                           Eigen::Index columns) const {
    const Eigen::Index s = data.directions->size();
    Eigen::MatrixXd q(parts.shard().rows(), columns);
    const int resume_after = kept_iteration(data.checkpoint, parts, s, columns);
    const PartKeeper* keep = data.checkpoint && parts.first() ? data.checkpoint : nullptr;
    if (resume_after >= 0) {
      log_info("resuming: the eigentransport fit after power iteration " +
               std::to_string(resume_after + 1) + " of " + std::to_string(power_iterations_) +
               ", kept in " + data.checkpoint->where());
      c.times(data.checkpoint->load_doubles(kept_z_name(resume_after)), q);
    } else {
      std::mt19937_64 rng(seed_);
      std::normal_distribution<double> gaussian;
      Eigen::MatrixXd omega(s, columns);
      for (auto& x : omega.reshaped()) x = gaussian(rng);
      c.times(omega, q);
    }
    orthonormalize_rows(q, parts);
    for (int i = resume_after + 1; i < power_iterations_; ++i) {
      Eigen::MatrixXd z = c.transpose_times(q);
      orthonormalize(z);
      if (keep) try {
          keep->save(kept_z_name(i), z);
          keep->save("eigen.iteration", Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, i)));
        } catch (const Error& e) {  // the fit goes on; only a rerun would miss the state
          log_warning(std::string("eigentransport: cannot keep the fit's state: ") + e.what());
          keep = nullptr;
        }
      c.times(z, q);
      orthonormalize_rows(q, parts);
    }
    return q;
  }

  // The eigentransports from the SVD of Q^T C: d functions (max_d, or fewer
  // by captured variance).
  void keep_functions(const Eigen::BDCSVD<Eigen::MatrixXd>& svd, double total_energy,
                      bool no_variance) {
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
    eigen_.resize(with_mean ? d : components, svd.matrixV().rows());
    if (with_mean) {
      eigen_.row(0) = outside / outside.norm();
      eigen_.bottomRows(components) = pcs;
    } else {
      eigen_ = pcs;
    }
    // The fraction of the variance the eigentransports hold (all of none).
    captured_variance_ =
        no_variance ? 1.0 : std::min(1.0, sigma.head(components).squaredNorm() / total_energy);
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
  // The column sums of T W (W = diag(sqrt(w)); a row per direction: sum_v c_vk sqrt(w_k)) and
  // ||T W||_F^2, by one product T^T [1, n] over the visible pairs: with
  // c_vk = n_v . d_k / pi, sum_v c_vk^2 = d_k . (sum_v c_vk n_v) / pi. One
  // packet per pair, where a pass of its own re-derived each cosine and
  // added it to a per-direction sum (0.13 s for the bunny, 8% of the fit).
  Eigen::RowVectorXd column_sums(const Mesh& mesh, const DirectionSet& set,
                                 const TransposedVisibility& transposed, const RowParts& parts,
                                 double& energy) const {
    const Shard shard = parts.shard();
    Eigen::MatrixXd ones_and_normals(shard.rows(), 4);
    for (Eigen::Index p = 0; p < shard.rows(); ++p)
      ones_and_normals.row(p) << 1.0,
          mesh.normals[std::size_t(shard.first + p)].cast<double>().transpose();
    const Eigen::MatrixXd sums =
        visible_transpose_sum(mesh, set, transposed, PaddedRows(ones_and_normals), parts);  // s x 4
    const Eigen::VectorXd weights = root_weights_.cwiseAbs2();
    const Eigen::VectorXd squares =
        (sums.rightCols<3>().cwiseProduct(set.directions).rowwise().sum() / M_PI);
    energy = weights.dot(squares);
    return sums.col(0).cwiseProduct(root_weights_).transpose();
  }

  static std::string kept_z_name(int iteration) { return "eigen.z." + std::to_string(iteration); }

  // The last power iteration a killed fit kept (rank 0 reads, and tells
  // every rank), or -1: none, or none that fits this fit's shape.
  int kept_iteration(const PartKeeper* store, const RowParts& parts, Eigen::Index s,
                     Eigen::Index columns) const {
    if (!store) return -1;
    std::vector<char> bytes(sizeof(std::int32_t), 0);
    std::int32_t iteration = -1;
    if (parts.first() && store->has("eigen.iteration")) try {
        const Eigen::MatrixXd kept = store->load_doubles("eigen.iteration");
        const int i = kept.size() == 1 ? static_cast<int>(kept(0, 0)) : -1;
        const Eigen::MatrixXd z = i >= 0 ? store->load_doubles(kept_z_name(i)) : Eigen::MatrixXd();
        if (i >= 0 && i < power_iterations_ && z.rows() == s && z.cols() == columns)
          iteration = i;
        else
          log_warning("eigentransport: the kept fit state does not fit this fit; starting afresh");
      } catch (const Error& e) {
        log_warning(std::string("eigentransport: the kept fit state is unreadable, starting "
                                "afresh: ") +
                    e.what());
      }
    std::memcpy(bytes.data(), &iteration, sizeof iteration);
    parts.broadcast(bytes, 0);
    std::memcpy(&iteration, bytes.data(), sizeof iteration);
    return iteration;
  }

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
