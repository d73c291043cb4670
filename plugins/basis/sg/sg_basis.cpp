// Spherical Gaussians G_i(d) = exp(lambda (mu_i . d - 1)) about centres mu_i
// on a Fibonacci set (Green et al. 2006; Tsai & Shih 2006 use spherical
// radial basis functions of this kind): smooth, local, all-frequency with
// enough lobes, and not orthonormal. The framework supplies the metric (its
// Gram matrix on the Gauss product rule): the default projection is least
// squares through G^-1 and relighting applies G (docs/bases.md). Sharpness
// is given relative to the lobe spacing, lambda = sharpness x lobes, so a
// lobe's width keeps its ratio to the spacing (and G its conditioning)
// whatever the count. The light rotates by re-projection: rotating the
// centres would change the basis.
#include <array>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/direction_set.hpp"
#include "prt/plugin.hpp"

namespace prt {

class SphericalGaussians final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "spherical Gaussians exp(lambda (mu_i.d - 1)) on a Fibonacci set (not orthonormal)";
  static constexpr auto kLobes =
      param::integer("lobes", "25", 1, 100, "number of Gaussians (Fibonacci centres)");
  static constexpr auto kSharpness =
      param::real("sharpness", "0.2", 0.1, 8,
                  "lambda / lobes: the lobes' width relative to their spacing (0.2: width about "
                  "0.63 x the spacing; 1: 0.28)");
  static constexpr auto parameters() { return param::records(kLobes, kSharpness); }

  explicit SphericalGaussians(const Params& params)
      : centres_(DirectionSet::fibonacci(static_cast<int>(kLobes(params))).directions),
        lambda_(kSharpness(params) * double(kLobes(params))) {}

  int size() const override { return static_cast<int>(centres_.rows()); }
  bool orthonormal() const override { return false; }

  Eigen::MatrixXd evaluate(const Directions& directions) const override {
    const Eigen::MatrixXd cosines = directions * centres_.transpose();
    return (lambda_ * (cosines.array() - 1.0)).exp().matrix();
  }

 private:
  Directions centres_;
  double lambda_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::SphericalGaussians, "sg")
