// Hemispherical harmonics (Gautron, Krivanek, Pattanaik, Bouatouch 2004): the
// associated Legendre functions of the shifted cosine 2 cos(theta) - 1, so
// that each function lives on the upper hemisphere only and the set is
// orthonormal there. An example of a hemisphere basis plug-in built outside
// the PRT tree; it serves as the exit basis of glossy transfer:
//   [exit]
//   plugin = "gautron"
//   order = 5
#include <array>
#include <cmath>
#include <prt/basis.hpp>
#include <prt/hemisphere.hpp>
#include <prt/plugin.hpp>

namespace example {

class HemisphericalHarmonics final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "Gautron et al.'s hemispherical harmonics, orthonormal over the upper hemisphere (example)";
  static constexpr auto parameters() {
    return std::array{prt::schema::integer("order", "5", 1, 20, "bands l < order (order^2 terms)")};
  }

  explicit HemisphericalHarmonics(const prt::Params& params)
      : order_(static_cast<int>(params.get_int("order"))) {}

  int size() const override { return order_ * order_; }
  prt::Domain domain() const override { return prt::Domain::hemisphere; }
  bool orthonormal() const override { return true; }

  // Index l (l + 1) + m, as the framework's SH; zero below the horizon.
  Eigen::MatrixXd evaluate(const prt::Directions& directions) const override {
    Eigen::MatrixXd values = Eigen::MatrixXd::Zero(directions.rows(), size());
    for (Eigen::Index k = 0; k < directions.rows(); ++k) {
      const double z = directions(k, 2);
      if (z < 0) continue;
      const double x = 2 * z - 1, s = std::sqrt(std::max(0.0, 1 - x * x));
      const double phi = std::atan2(directions(k, 1), directions(k, 0));
      for (int m = 0; m < order_; ++m) {
        // P_m^m(x) = (2m - 1)!! s^m, then upward in l.
        double p_mm = 1;
        for (int i = 1; i <= m; ++i) p_mm *= (2 * i - 1) * s;
        double previous = 0, p = p_mm;
        for (int l = m; l < order_; ++l) {
          if (l == m + 1) previous = p, p = x * (2 * m + 1) * p_mm;
          if (l > m + 1) {
            const double next = ((2 * l - 1) * x * p - (l + m - 1) * previous) / (l - m);
            previous = p, p = next;
          }
          const double norm = normalisation(l, m);
          if (m == 0) {
            values(k, l * (l + 1)) = norm * p;
          } else {
            values(k, l * (l + 1) + m) = std::sqrt(2.0) * norm * std::cos(m * phi) * p;
            values(k, l * (l + 1) - m) = std::sqrt(2.0) * norm * std::sin(m * phi) * p;
          }
        }
      }
    }
    return values;
  }

  // Functions known over the whole sphere are projected over the upper half.
  Eigen::MatrixXd projection_matrix(const prt::DirectionSet& set) const override {
    Eigen::VectorXd upper = set.weights;
    for (Eigen::Index k = 0; k < set.size(); ++k)
      if (set.directions(k, 2) <= 0) upper[k] = 0;
    return upper.asDiagonal() * evaluate(set.directions);
  }

  // Gauss-Legendre in cos(theta) x uniform phi: exact for these products.
  std::optional<prt::DirectionSet> native_directions() const override {
    return prt::hemisphere::upper_quadrature(order_ + 1);
  }

 private:
  // K_l^m = sqrt((2l + 1) (l - m)! / (2 pi (l + m)!)): orthonormal over the
  // hemisphere, whose measure is half the sphere's.
  static double normalisation(int l, int m) {
    double ratio = 1;  // (l - m)! / (l + m)!
    for (int i = l - m + 1; i <= l + m; ++i) ratio /= i;
    return std::sqrt((2 * l + 1) * ratio / (2 * M_PI));
  }

  int order_;
};

}  // namespace example

PRT_EXPORT_PLUGIN(example::HemisphericalHarmonics, "gautron")
