// Real spherical harmonics (prt/sh.hpp conventions) as a basis plug-in.
#include <array>

#include "prt/basis.hpp"
#include "prt/plugin.hpp"
#include "prt/sh.hpp"

namespace prt {

class SphericalHarmonics final : public Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "real orthonormal spherical harmonics, order^2 coefficients, with rotation";
  static constexpr auto kOrder =
      param::integer("order", "6", 1, 200, "number of bands l = 0..order-1 (order^2 terms)");
  static constexpr auto parameters() { return param::records(kOrder); }

  explicit SphericalHarmonics(const Params& params) : order_(static_cast<int>(kOrder(params))) {}

  int size() const override { return sh::coefficient_count(order_); }
  bool orthonormal() const override { return true; }
  Eigen::MatrixXd evaluate(const Directions& directions) const override {
    return sh::evaluate(order_, directions);
  }
  std::vector<int> coefficient_bands() const override {
    std::vector<int> bands;
    for (int l = 0; l < order_; ++l) bands.insert(bands.end(), 2 * l + 1, l);
    return bands;
  }
  std::optional<Eigen::MatrixX3d> project_equirect(int width, int height,
                                                   const float* rgb) const override {
    return sh::project_equirect(order_, width, height, rgb);
  }
  bool can_rotate() const override { return true; }
  Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d& rotation) const override {
    return sh::rotation(order_, rotation);
  }

 private:
  int order_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::SphericalHarmonics, "sh")
