// Importance sampling of an environment map: directions drawn with
// probability proportional to luminance x texel solid angle, so Monte Carlo
// ground truth converges under HDR maps with a small bright sun.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "prt/environment.hpp"

namespace prt {

class EnvironmentSampler {
 public:
  explicit EnvironmentSampler(const Environment& environment);

  struct Sample {
    Eigen::Vector3d direction;  // world space (the map's rotation applied)
    double pdf;                 // per unit solid angle
  };
  // Maps two uniform numbers in [0, 1) to a direction.
  Sample sample(double u1, double u2) const;
  // Density of sample() at a world direction.
  double pdf(const Eigen::Vector3d& direction) const;

 private:
  int width_, height_;
  Eigen::Matrix3d rotation_;
  std::vector<double> row_cdf_;            // height + 1
  std::vector<double> column_cdf_;         // height x (width + 1)
  std::vector<double> texel_probability_;  // height x width
};

}  // namespace prt
