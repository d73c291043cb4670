// Zonal harmonics: the m = 0 spherical harmonics about +z, orthonormal over
// the sphere. An example of a basis plug-in built outside the PRT tree.
#include <array>
#include <cmath>
#include <prt/basis.hpp>
#include <prt/plugin.hpp>

namespace example {

class ZonalHarmonics final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "zonal harmonics y_l0 about +z (example)";
  // Each parameter declared once: its schema record and its typed reader.
  static constexpr auto kOrder = prt::param::integer("order", "8", 1, 64, "number of bands");
  static constexpr auto parameters() { return prt::param::records(kOrder); }

  explicit ZonalHarmonics(const prt::Params& params) : order_(static_cast<int>(kOrder(params))) {}

  int size() const override { return order_; }
  bool orthonormal() const override { return true; }

  Eigen::MatrixXd evaluate(const prt::Directions& directions) const override {
    Eigen::MatrixXd values(directions.rows(), order_);
    for (Eigen::Index k = 0; k < directions.rows(); ++k) {
      const double z = directions(k, 2);
      double previous = 0.0, legendre = 1.0;  // P_{l-1}(z), P_l(z)
      for (int l = 0; l < order_; ++l) {
        values(k, l) = std::sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * legendre;
        const double next = ((2.0 * l + 1.0) * z * legendre - l * previous) / (l + 1.0);
        previous = legendre;
        legendre = next;
      }
    }
    return values;
  }

 private:
  int order_;
};

}  // namespace example

PRT_EXPORT_PLUGIN(example::ZonalHarmonics, "zonal")
