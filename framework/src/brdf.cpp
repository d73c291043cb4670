#include "prt/brdf.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>

#include "prt/error.hpp"
#include "prt/hemisphere.hpp"
#include "prt/sh.hpp"

namespace prt {

BrdfModel brdf_model(const std::string& name) {
  if (name == "lambert") return BrdfModel::lambert;
  if (name == "phong") return BrdfModel::phong;
  if (name == "ward") return BrdfModel::ward;
  if (name == "cook-torrance") return BrdfModel::cook_torrance;
  throw Error("unknown BRDF \"" + name + "\"; valid: lambert, phong, ward, cook-torrance");
}

double Brdf::evaluate(const Eigen::Vector3d& in, const Eigen::Vector3d& out) const {
  const double cos_in = in.z(), cos_out = out.z();
  if (cos_in <= 0 || cos_out <= 0) return 0.0;
  double value = kd / M_PI;
  if (ks == 0) return value;
  if (model == BrdfModel::phong) {
    const Eigen::Vector3d mirror(-in.x(), -in.y(), in.z());
    const double c = mirror.dot(out);
    if (c > 0) value += ks * (exponent + 2) / (2 * M_PI) * std::pow(c, exponent);
    return value;
  }
  const Eigen::Vector3d h = (in + out).normalized();
  if (model == BrdfModel::ward) {
    const double e = (h.x() * h.x() / (alpha_x * alpha_x) + h.y() * h.y() / (alpha_y * alpha_y)) /
                     (h.z() * h.z());
    return value + ks * std::exp(-e) / (4 * M_PI * alpha_x * alpha_y * std::sqrt(cos_in * cos_out));
  }
  // Cook-Torrance: Beckmann D, Schlick F, Torrance-Sparrow G.
  const double nh = h.z(), vh = std::max(1e-12, out.dot(h)), m2 = roughness * roughness;
  const double tan2 = (1 - nh * nh) / (nh * nh);
  const double d = std::exp(-tan2 / m2) / (M_PI * m2 * nh * nh * nh * nh);
  const double f = f0 + (1 - f0) * std::pow(1 - vh, 5);
  const double g = std::min({1.0, 2 * nh * cos_out / vh, 2 * nh * cos_in / vh});
  return value + ks * d * f * g / (4 * cos_in * cos_out);
}

std::string Brdf::describe() const {
  char text[256];
  switch (model) {
    case BrdfModel::phong:
      std::snprintf(text, sizeof text, "phong kd=%g ks=%g exponent=%g", kd, ks, exponent);
      break;
    case BrdfModel::ward:
      std::snprintf(text, sizeof text, "ward kd=%g ks=%g alpha=(%g, %g)", kd, ks, alpha_x, alpha_y);
      break;
    case BrdfModel::cook_torrance:
      std::snprintf(text, sizeof text, "cook-torrance kd=%g ks=%g m=%g f0=%g", kd, ks, roughness,
                    f0);
      break;
    case BrdfModel::lambert:
      std::snprintf(text, sizeof text, "lambert kd=%g", kd);
      break;
  }
  return text;
}

Eigen::MatrixXd brdf_incident_integrals(const Brdf& brdf, const Directions& exit_directions,
                                        int incident_order, int resolution) {
  const DirectionSet h = hemisphere::upper_quadrature(resolution);
  // Incident side: y_j(s) s_z w_s, so that F = rho * light is int rho y_j s_z ds.
  Eigen::MatrixXd light = sh::evaluate(incident_order, h.directions);
  for (Eigen::Index k = 0; k < h.size(); ++k) light.row(k) *= h.weights[k] * h.directions(k, 2);
  Eigen::MatrixXd f(exit_directions.rows(), light.cols());
  tbb::parallel_for(Eigen::Index(0), exit_directions.rows(), [&](Eigen::Index v) {
    const Eigen::Vector3d out = exit_directions.row(v).transpose();
    Eigen::RowVectorXd rho(h.size());
    for (Eigen::Index s = 0; s < h.size(); ++s)
      rho[s] = brdf.evaluate(h.directions.row(s).transpose(), out);
    f.row(v) = rho * light;
  });
  return f;
}

Eigen::MatrixXd brdf_matrix(const Brdf& brdf, int exit_order, const std::vector<int>& exit_kept,
                            int light_order, int resolution) {
  const DirectionSet h = hemisphere::upper_quadrature(resolution);
  const Eigen::MatrixXd exit_all = sh::evaluate(exit_order, h.directions);
  Eigen::MatrixXd exit(h.size(), static_cast<Eigen::Index>(exit_kept.size()));
  for (std::size_t i = 0; i < exit_kept.size(); ++i) exit.col(i) = exit_all.col(exit_kept[i]);
  return exit.transpose() * h.weights.asDiagonal() *
         brdf_incident_integrals(brdf, h.directions, light_order, resolution);
}

}  // namespace prt
