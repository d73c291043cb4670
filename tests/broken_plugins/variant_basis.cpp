// Order-3 SH with a boolean "drop_constant" (9 or 8 functions), built once
// correct and once per bug a researcher makes (tests/integration/
// kit_catches_variants.sh): PRT_BUG_NORMALISATION (one function scaled),
// PRT_BUG_WEIGHTS (native weights doubled and functions scaled to match, so
// the basis looks orthonormal on its own rule), PRT_BUG_SIZE (size() ignores
// the boolean), PRT_BUG_REFLECTION (the "rotation" also mirrors z),
// PRT_BUG_LOCAL_FIT (fits distributed, but sums only its own rank's shard),
// PRT_BUG_CLAIMS_ORTHONORMAL (functions mixed so that they overlap, still
// claiming orthonormality), PRT_BUG_GRAM_FACTOR (the same mixed functions,
// honestly not orthonormal, but projected by its own least squares with a
// Gram matrix 10% too large), PRT_BUG_HORIZON (a hemisphere basis, an exit
// basis, honest about its metric, whose least squares leaves out the band
// near the horizon: fine where it was fitted, wrong toward grazing views).
#include <Eigen/LU>
#include <array>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/hemisphere.hpp"
#include "prt/plugin.hpp"
#include "prt/quadrature.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"

namespace {

class VariantBasis final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "0.0.1";
  static constexpr const char* plugin_description = "test plug-in: SH order 3, maybe broken";
  static constexpr auto parameters() {
    return std::array{prt::schema::boolean("drop_constant", "false", "leave out y_00")};
  }
  explicit VariantBasis(const prt::Params& params) : drop_(params.get_bool("drop_constant")) {}

  int size() const override {
#ifdef PRT_BUG_SIZE
    return 9;
#else
    return drop_ ? 8 : 9;
#endif
  }
#ifdef PRT_BUG_HORIZON
  prt::Domain domain() const override {
    return prt::Domain::hemisphere;
  }
  Eigen::MatrixXd projection_matrix(const prt::DirectionSet& set) const override {
    Eigen::VectorXd weights = set.weights;
    for (Eigen::Index k = 0; k < set.size(); ++k)
      if (set.directions(k, 2) < 0.5) weights[k] = 0;  // "the horizon hardly matters"
    const Eigen::MatrixXd b = evaluate(set.directions);
    const Eigen::MatrixXd gram = b.transpose() * weights.asDiagonal() * b;
    return weights.asDiagonal() * b * gram.inverse();
  }
#endif
  bool orthonormal() const override {
#if defined(PRT_BUG_GRAM_FACTOR) || defined(PRT_BUG_HORIZON)
    return false;
#else
    return true;
#endif
  }
  Eigen::MatrixXd evaluate(const prt::Directions& d) const override {
    Eigen::MatrixXd all = prt::sh::evaluate(3, d);
#if defined(PRT_BUG_CLAIMS_ORTHONORMAL) || defined(PRT_BUG_GRAM_FACTOR)
    all.col(2) += 0.5 * all.col(0);  // overlapping functions: G is not the identity
    all.col(6) += 0.3 * all.col(4);
#endif
#ifdef PRT_BUG_NORMALISATION
    all.col(5) *= 1.05;
#endif
#ifdef PRT_BUG_WEIGHTS
    all /= std::sqrt(2.0);
#endif
    return drop_ ? Eigen::MatrixXd(all.rightCols(8)) : all;
  }
  std::optional<prt::DirectionSet> native_directions() const override {
#ifdef PRT_BUG_HORIZON
    prt::DirectionSet set = prt::hemisphere::upper_quadrature(6);
#else
    prt::DirectionSet set = prt::gauss_product_sphere(6);
#endif
#ifdef PRT_BUG_WEIGHTS
    set.weights *= 2.0;
#endif
    return set;
  }
  std::vector<int> coefficient_bands() const override {
    std::vector<int> bands{0, 1, 1, 1, 2, 2, 2, 2, 2};
    if (drop_) bands.erase(bands.begin());
    return bands;
  }
  bool can_rotate() const override {
    return true;
  }
#ifdef PRT_BUG_GRAM_FACTOR
  // Least squares of its own, through a Gram matrix off by a factor.
  Eigen::MatrixXd projection_matrix(const prt::DirectionSet& set) const override {
    const prt::DirectionSet rule = prt::gauss_product_sphere(6);
    const Eigen::MatrixXd b = evaluate(rule.directions);
    const Eigen::MatrixXd gram = 1.1 * (b.transpose() * rule.weights.asDiagonal() * b);
    return set.weights.asDiagonal() * evaluate(set.directions) * gram.inverse();
  }
#endif
#ifdef PRT_BUG_LOCAL_FIT
  // "Fitted" state that leaves the functions alone: the fraction of visible
  // (vertex, direction) pairs, counted over this rank's shard only.
  bool can_fit() const override {
    return true;
  }
  bool can_fit_distributed() const override {
    return true;
  }
  void fit(const prt::FitData& data) override {
    double visible = 0;
    for (std::size_t v = 0; v < data.visibility->vertices(); ++v)
      visible += double(data.visibility->count_visible(v));
    visible_fraction_ = visible / double(data.visibility->vertices() *
                                         std::max<std::size_t>(1, data.visibility->directions()));
  }
  prt::BasisState save() const override {
    prt::BasisState state;
    state.matrices["visible_fraction"] = Eigen::MatrixXd::Constant(1, 1, visible_fraction_);
    return state;
  }
  void load(const prt::BasisState& state) override {
    visible_fraction_ = state.matrices.at("visible_fraction")(0, 0);
  }
  double visible_fraction_ = 0;
#endif
  Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d& r) const override {
    Eigen::MatrixXd m = prt::sh::rotation(3, r);
#ifdef PRT_BUG_REFLECTION
    // Mirror z after rotating: (-1)^(l+m) per coefficient, a reflection.
    for (int l = 0, i = 0; l < 3; ++l)
      for (int k = -l; k <= l; ++k, ++i) m.row(i) *= ((l + k) % 2 == 0) ? 1.0 : -1.0;
#endif
    return drop_ ? Eigen::MatrixXd(m.bottomRightCorner(8, 8)) : m;
  }

 private:
  bool drop_;
};

}  // namespace

PRT_EXPORT_PLUGIN(VariantBasis, "variant")
