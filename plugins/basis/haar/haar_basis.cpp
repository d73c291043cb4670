// Haar wavelets on the cube map (Ng, Ramamoorthi & Hanrahan 2003): on each of
// the six R x R faces, the orthonormal non-standard 2-D Haar decomposition.
//
// Solid angle: a function sampled at the texel directions with weights w_t
// is transformed as f_t sqrt(w_t), so the basis functions are
// b_i(t) = H_i(t) / sqrt(w_t) with H the orthogonal Haar matrix. They are then
// orthonormal under the lattice's quadrature, sum_t w_t b_i b_j = delta_ij, and
// projection on the cube map followed by reconstruction is exact with all
// coefficients. The transform is O(s) per function, never an s x s matrix.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "prt/basis.hpp"
#include "prt/log.hpp"
#include "prt/plugin.hpp"

namespace prt {

class HaarCubeMap final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "orthonormal 2-D Haar wavelets on each cube-map face (6 R^2 coefficients)";
  static constexpr auto kResolution =
      param::integer("resolution", "16", 1, 256, "texels per face edge R (a power of 2)");
  static constexpr auto kKept =
      param::integer("k", "0", 0, 1 << 30,
                     "non-linear approximation: largest coefficients kept per vertex (0 = all)");
  static constexpr auto parameters() { return param::records(kResolution, kKept); }

  explicit HaarCubeMap(const Params& params)
      : resolution_(static_cast<int>(kResolution(params))),
        k_(static_cast<int>(kKept(params))),
        lattice_(DirectionSet::cubemap(resolution_)) {
    if (resolution_ & (resolution_ - 1))
      params.fail(kResolution.name(), "must be a power of 2, got " + std::to_string(resolution_));
    root_weights_ = lattice_.weights.cwiseSqrt();
    if (k_ > size()) {  // keeping more than there is keeps all: say so
      log_warning_once(params.location("k").str() + ": basis \"haar\": k = " + std::to_string(k_) +
                       " is more than its " + std::to_string(size()) +
                       " coefficients (resolution " + std::to_string(resolution_) + "); " +
                       std::to_string(size()) + " used");
      k_ = size();
    }
  }

  int size() const override { return 6 * resolution_ * resolution_; }
  bool orthonormal() const override { return true; }
  int approximation_terms() const override { return k_; }

  // b_i at the texel containing each direction.
  Eigen::MatrixXd evaluate(const Directions& directions) const override {
    Eigen::MatrixXd values = Eigen::MatrixXd::Zero(directions.rows(), size());
    Eigen::VectorXd delta(size());
    for (Eigen::Index k = 0; k < directions.rows(); ++k) {
      const int t = texel_of(directions.row(k).transpose());
      delta.setZero();
      delta[t] = 1.0 / root_weights_[t];
      forward(delta.data());  // H e_t / sqrt(w_t): row t of H^T, scaled
      values.row(k) = delta.transpose();
    }
    return values;
  }

  // Any set projects in O(s): c_i = sum_k w_k f_k b_i(d_k) = (H G)_i with
  // G_t = sum_{k in texel t} w_k f_k / sqrt(w_t), then one fast transform.
  bool has_fast_projection(const DirectionSet&) const override { return true; }

  Eigen::MatrixXd project(const Eigen::MatrixXd& samples, const DirectionSet& set) const override {
    if (samples.cols() != set.size())
      throw Error("haar: " + std::to_string(samples.cols()) + " samples per function for " +
                  std::to_string(set.size()) + " directions");
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out;
    if (is_lattice(set)) {
      out = samples * root_weights_.asDiagonal();
    } else {
      std::vector<int> texel(set.size());
      for (Eigen::Index k = 0; k < set.size(); ++k)
        texel[k] = texel_of(set.directions.row(k).transpose());
      out = Eigen::MatrixXd::Zero(samples.rows(), size());
      for (Eigen::Index r = 0; r < samples.rows(); ++r)
        for (Eigen::Index k = 0; k < set.size(); ++k)
          out(r, texel[k]) += set.weights[k] * samples(r, k) / root_weights_[texel[k]];
    }
    for (Eigen::Index r = 0; r < out.rows(); ++r) forward(out.row(r).data());
    return out;
  }

  std::optional<DirectionSet> native_directions() const override { return lattice_; }

 private:
  bool is_lattice(const DirectionSet& set) const {
    return set.kind == "cubemap" && set.size() == size();
  }

  int texel_of(const Eigen::Vector3d& d) const { return cubemap_texel(d, resolution_); }

  // In-place non-standard 2-D Haar transform of each face (orthonormal):
  // per level, each 2 x 2 block becomes its average and three details, the
  // averages gathered in the top-left quadrant.
  void forward(double* data) const {
    const int R = resolution_;
    std::vector<double> scratch(static_cast<std::size_t>(R) * R);
    for (int face = 0; face < 6; ++face) {
      double* f = data + static_cast<std::size_t>(face) * R * R;
      for (int width = R; width > 1; width /= 2) {
        const int half = width / 2;
        for (int j = 0; j < half; ++j)
          for (int i = 0; i < half; ++i) {
            const double a = f[(2 * j) * R + 2 * i], b = f[(2 * j) * R + 2 * i + 1];
            const double c = f[(2 * j + 1) * R + 2 * i], d = f[(2 * j + 1) * R + 2 * i + 1];
            scratch[j * R + i] = 0.5 * (a + b + c + d);
            scratch[j * R + i + half] = 0.5 * (a - b + c - d);
            scratch[(j + half) * R + i] = 0.5 * (a + b - c - d);
            scratch[(j + half) * R + i + half] = 0.5 * (a - b - c + d);
          }
        for (int j = 0; j < width; ++j)
          for (int i = 0; i < width; ++i) f[j * R + i] = scratch[j * R + i];
      }
    }
  }

  int resolution_, k_;
  DirectionSet lattice_;
  Eigen::VectorXd root_weights_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::HaarCubeMap, "haar")
