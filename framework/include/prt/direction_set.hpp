// Sets of unit directions with quadrature weights (solid angle per sample),
// shared by every basis so one set of rays serves all of them.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace prt {

using Directions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct DirectionSet {
  std::string kind;         // "fibonacci", "stratified", "cubemap", "equirect", ...
  Directions directions;    // s x 3, unit length
  Eigen::VectorXd weights;  // s, solid angle of each sample; sums to 4 pi over the sphere

  Eigen::Index size() const { return directions.rows(); }

  // Spherical Fibonacci lattice: near-uniform, equal weights.
  static DirectionSet fibonacci(int count);
  // Jittered strata in (cos theta, phi): unbiased for any integrand, seeded.
  static DirectionSet stratified(int count, std::uint64_t seed);
  // Texel centres of a cube map with R x R texels per face (6 R^2 directions),
  // weighted by each texel's exact solid angle. Face order +X -X +Y -Y +Z -Z.
  static DirectionSet cubemap(int resolution);
  // Texel centres of an equirectangular W x H map, rows [row_begin, row_end).
  static DirectionSet equirect(int width, int height, int row_begin, int row_end);

  // Builds the set named in a scene ("fibonacci", "stratified", "cubemap").
  // For "cubemap" `count` is rounded to the nearest 6 R^2.
  static DirectionSet make(const std::string& kind, int count, std::uint64_t seed);
};

// Cube-map face (+X -X +Y -Y +Z -Z) of a direction and its coordinates (a, b)
// in [-1, 1] on that face, as DirectionSet::cubemap lays texels out.
void cubemap_coordinates(const Eigen::Vector3d& direction, int& face, double& a, double& b);

// Index of the cube-map texel (resolution R) containing a direction, in the
// order of DirectionSet::cubemap: (face * R + row) * R + column.
int cubemap_texel(const Eigen::Vector3d& direction, int resolution);

// Equirectangular convention (y up): u = 0.5 + atan2(x, -z) / 2 pi, v = acos(y) / pi.
Eigen::Vector3d equirect_direction(double u, double v);
Eigen::Vector2d equirect_uv(const Eigen::Vector3d& direction);

}  // namespace prt
