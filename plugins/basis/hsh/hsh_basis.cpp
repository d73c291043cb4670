// Spherical harmonics over the upper hemisphere (z > 0 in the local frame),
// Sloan et al. 2003 §3.2: functions known on H only are projected by least
// squares, c = A^-1 b, through the framework's SVD with a cut-off, or by the
// zero-hemisphere or odd/even-reflection projections for comparison.
#include <array>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/hemisphere.hpp"
#include "prt/plugin.hpp"
#include "prt/sh.hpp"

namespace prt {

class HemisphericalHarmonics final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "SH over the upper hemisphere with least-squares (or zero/odd/even) projection";
  static constexpr auto kOrder =
      param::integer("order", "5", 1, 30, "SH order N (N^2 functions, N^2 - 1 when reduced)");
  static constexpr auto kProjection =
      param::choice("projection", "least-squares", "least-squares|zero|odd|even",
                    "how functions known on the hemisphere are projected");
  static constexpr auto kCutoff =
      param::real("cutoff", "1e-10", 0, 1,
                  "least squares: singular values of A below this x the largest are discarded");
  static constexpr auto kReduced = param::boolean(
      "reduced", "false", "drop the nearly redundant l=1, m=0 function (N_i = 24 at order 5)");
  static constexpr auto parameters() {
    return param::records(kOrder, kProjection, kCutoff, kReduced);
  }

  explicit HemisphericalHarmonics(const Params& params)
      : order_(static_cast<int>(kOrder(params))), projection_(projection_of(params)) {
    const bool reduced = kReduced(params);
    if (reduced && projection_ != Projection::least_squares)
      params.fail(kReduced.name(), "the reduced basis needs projection = \"least-squares\"");
    if (reduced && order_ < 2) params.fail(kReduced.name(), "the reduced basis needs order >= 2");
    ls_ = hemisphere::least_squares(order_, kCutoff(params), reduced ? sh::index(1, 0) : -1);
  }

  int size() const override { return static_cast<int>(ls_.kept.size()); }
  Domain domain() const override { return Domain::hemisphere; }
  bool orthonormal() const override { return false; }

  Eigen::MatrixXd evaluate(const Directions& directions) const override {
    const Eigen::MatrixXd all = sh::evaluate(order_, directions);
    Eigen::MatrixXd kept(all.rows(), size());
    for (int i = 0; i < size(); ++i) kept.col(i) = all.col(ls_.kept[i]);
    return kept;
  }

  // Samples below the horizon are ignored: P = W_H Y (projection matrix of
  // the chosen method), so coefficients = samples * P.
  Eigen::MatrixXd projection_matrix(const DirectionSet& set) const override {
    Eigen::VectorXd upper = set.weights;
    for (Eigen::Index k = 0; k < set.size(); ++k)
      if (set.directions(k, 2) <= 0) upper[k] = 0;
    const Eigen::MatrixXd b = upper.asDiagonal() * evaluate(set.directions);  // zero-hemisphere
    if (projection_ == Projection::least_squares) return b * ls_.inverse;     // A symmetric
    if (projection_ == Projection::zero) return b;
    // Reflection: the extended function's projection is 2 b on one parity, 0 on the other.
    Eigen::MatrixXd p = b;
    for (int i = 0; i < size(); ++i) {
      const int index = ls_.kept[i];
      const int l = static_cast<int>(std::sqrt(double(index)));
      const bool odd_parity = ((l + std::abs(index - l * (l + 1))) % 2) == 1;
      p.col(i) *= (odd_parity == (projection_ == Projection::odd)) ? 2.0 : 0.0;
    }
    return p;
  }

  std::optional<DirectionSet> native_directions() const override {
    return hemisphere::upper_quadrature(order_ + 1);
  }

  BasisState save() const override { return {{{"gram_inverse", ls_.inverse}}}; }

 private:
  enum class Projection { least_squares, zero, odd, even };
  static Projection projection_of(const Params& params) {
    const std::string name = kProjection(params);
    if (name == "least-squares") return Projection::least_squares;
    if (name == "zero") return Projection::zero;
    if (name == "odd") return Projection::odd;
    if (name == "even") return Projection::even;
    params.fail(kProjection.name(), "unknown value \"" + name + "\"");
  }

  int order_;
  Projection projection_;
  hemisphere::LeastSquares ls_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::HemisphericalHarmonics, "hsh")
