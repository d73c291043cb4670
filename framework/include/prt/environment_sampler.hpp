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
    Eigen::Vector2d uv;         // the map coordinates of the centre of its texel
  };
  // Maps two uniform numbers in [0, 1) to a direction.
  Sample sample(double u1, double u2) const;
  // The same without its density, which density(texel) reads later (a
  // caller that draws many samples first).
  struct Drawn {
    Eigen::Vector3d direction;
    Eigen::Index texel;  // y width + x
  };
  Drawn draw(double u1, double u2) const;
  // The texel of map coordinates, and the density of sample() in a texel
  // (per unit solid angle: pdf_at of any point in it).
  Eigen::Index texel_at(const Eigen::Vector2d& uv) const;
  double density(Eigen::Index texel) const {
    return texel_probability_[std::size_t(texel)] / texel_solid_angle_[std::size_t(texel / width_)];
  }
  // Density of sample() at a world direction.
  double pdf(const Eigen::Vector3d& direction) const;
  // The same at map coordinates (Environment::uv_of of the direction).
  double pdf_at(const Eigen::Vector2d& uv) const;

 private:
  int width_, height_;
  Eigen::Matrix3d rotation_;
  std::vector<double> row_cdf_;            // height + 1
  std::vector<double> column_cdf_;         // height x (width + 1)
  std::vector<double> texel_probability_;  // height x width
  // Per row, computed once (sample() and pdf() ran four cosines a call):
  std::vector<double> row_z_;              // cos(pi y / height), height + 1
  std::vector<double> texel_solid_angle_;  // of a texel of row y, height
};

}  // namespace prt
