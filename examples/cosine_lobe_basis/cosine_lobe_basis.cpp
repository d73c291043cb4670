// Cosine lobes ((1 + w . d_i) / 2)^p about centres d_i on a Fibonacci set:
// smooth, local, and not orthonormal (neighbouring lobes overlap). An example
// of a basis plug-in that says so (orthonormal() is false) and leaves the
// rest to the framework: its default projection is least squares through the
// Gram matrix, and relighting applies the metric (docs/bases.md, "The metric
// of a basis"). With orthonormalise = true it is the same span made
// orthonormal by G^-1/2, which must relight identically.
#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <prt/basis.hpp>
#include <prt/direction_set.hpp>
#include <prt/plugin.hpp>
#include <prt/quadrature.hpp>

namespace example {

class CosineLobes final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "cosine lobes ((1 + w.d_i)/2)^p on a Fibonacci set (example; not orthonormal)";
  static constexpr auto parameters() {
    using namespace prt::schema;
    // Lobes of power p span the polynomials of degree <= p, (p + 1)^2
    // functions: 25 lobes need p >= 4 to be independent, which the ranges keep.
    return std::array{integer("lobes", "25", 1, 25, "number of lobes (Fibonacci centres)"),
                      integer("power", "4", 4, 16, "the lobes' exponent p (sharper when larger)"),
                      boolean("orthonormalise", "false",
                              "use the orthonormal functions G^-1/2 B of the same span")};
  }

  explicit CosineLobes(const prt::Params& params)
      : power_(static_cast<int>(params.get_int("power"))),
        orthonormalise_(params.get_bool("orthonormalise")),
        centres_(
            prt::DirectionSet::fibonacci(static_cast<int>(params.get_int("lobes"))).directions) {
    if (!orthonormalise_) return;
    // G on a rule exact for the products of two lobes (degree 2p).
    const prt::DirectionSet rule = prt::gauss_product_sphere(power_ + 2);
    const Eigen::MatrixXd b = lobes(rule.directions);
    const Eigen::MatrixXd gram = b.transpose() * rule.weights.asDiagonal() * b;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
    mix_ = eigen.eigenvectors() * eigen.eigenvalues().cwiseInverse().cwiseSqrt().asDiagonal() *
           eigen.eigenvectors().transpose();
  }

  int size() const override { return static_cast<int>(centres_.rows()); }
  bool orthonormal() const override { return orthonormalise_; }

  Eigen::MatrixXd evaluate(const prt::Directions& directions) const override {
    return orthonormalise_ ? Eigen::MatrixXd(lobes(directions) * mix_) : lobes(directions);
  }

 private:
  Eigen::MatrixXd lobes(const prt::Directions& directions) const {
    const Eigen::MatrixXd cosines = directions * centres_.transpose();
    return ((1.0 + cosines.array()) / 2.0).pow(power_).matrix();
  }

  int power_;
  bool orthonormalise_;
  prt::Directions centres_;
  Eigen::MatrixXd mix_;  // G^-1/2 when orthonormalised
};

}  // namespace example

PRT_EXPORT_PLUGIN(example::CosineLobes, "lobes")
