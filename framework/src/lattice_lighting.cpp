#include "prt/lattice_lighting.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "prt/error.hpp"

namespace prt {

Eigen::MatrixX3d lattice_lighting(const Environment& env, int resolution) {
  const DirectionSet lattice = DirectionSet::cubemap(resolution);
  Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(lattice.size(), 3);
  Eigen::VectorXd area = Eigen::VectorXd::Zero(lattice.size());
  Environment canonical = env;
  canonical.set_rotation(Eigen::Matrix3d::Identity());
  // Bin the map's texels (with their solid angles) into the cube texels; a
  // constant map is sampled at 4 x 4 points per cube texel instead.
  const int w = std::max(env.width(), 8 * resolution), h = std::max(env.height(), 4 * resolution);
  for (int y = 0; y < h; ++y) {
    const DirectionSet row = DirectionSet::equirect(w, h, y, y + 1);
    for (Eigen::Index k = 0; k < row.size(); ++k) {
      const Eigen::Vector3d d = row.directions.row(k).transpose();
      const int t = cubemap_texel(d, resolution);
      sum.row(t) += row.weights[k] * canonical.texel_radiance(d).cast<double>().transpose();
      area[t] += row.weights[k];
    }
  }
  for (Eigen::Index t = 0; t < lattice.size(); ++t)
    sum.row(t) = area[t] > 0 ? Eigen::RowVector3d(sum.row(t) / area[t])
                             : canonical.texel_radiance(lattice.directions.row(t).transpose())
                                   .cast<double>()
                                   .transpose();
  return sum;
}

Eigen::MatrixX3d rotate_lattice_lighting(const Eigen::MatrixX3d& samples, int resolution,
                                         const Eigen::Matrix3d& rotation) {
  const DirectionSet lattice = DirectionSet::cubemap(resolution);
  if (samples.rows() != lattice.size())
    throw Error("rotate_lattice_lighting: samples do not match the cube map");
  const int r = resolution;
  Eigen::MatrixX3d out(lattice.size(), 3);
  tbb::parallel_for(Eigen::Index(0), lattice.size(), [&](Eigen::Index k) {
    const Eigen::Vector3d d = rotation.transpose() * lattice.directions.row(k).transpose();
    int face;
    double a, b;
    cubemap_coordinates(d, face, a, b);
    // Texel-centre coordinates: texel i covers [i, i+1) in (a + 1) r / 2.
    const double x = std::clamp((a + 1) * 0.5 * r - 0.5, 0.0, r - 1.0);
    const double y = std::clamp((b + 1) * 0.5 * r - 0.5, 0.0, r - 1.0);
    const int x0 = std::min(static_cast<int>(x), r - 1), y0 = std::min(static_cast<int>(y), r - 1);
    const int x1 = std::min(x0 + 1, r - 1), y1 = std::min(y0 + 1, r - 1);
    const double fx = x - x0, fy = y - y0;
    auto at = [&](int i, int j) { return samples.row((face * r + j) * r + i); };
    out.row(k) = (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) +
                 fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
  });
  return out;
}

std::optional<LatticeRotation> LatticeRotation::of(const Basis& basis,
                                                   const Environment& environment) {
  if (basis.can_rotate()) return std::nullopt;
  const std::optional<DirectionSet> native = basis.native_directions();
  if (!native || native->kind != "cubemap") return std::nullopt;
  LatticeRotation out;
  out.basis_ = &basis;
  out.resolution_ = static_cast<int>(std::lround(std::sqrt(native->size() / 6.0)));
  if (6 * out.resolution_ * out.resolution_ != native->size()) return std::nullopt;
  out.lattice_ = *native;
  out.canonical_ = lattice_lighting(environment, out.resolution_);
  return out;
}

Eigen::MatrixX3d LatticeRotation::light(const Eigen::Matrix3d& rotation) const {
  const Eigen::MatrixX3d samples = rotation.isIdentity(1e-12)
                                       ? canonical_
                                       : rotate_lattice_lighting(canonical_, resolution_, rotation);
  const Eigen::MatrixXd light = basis_->project(samples.transpose(), lattice_).transpose();
  if (light.rows() != basis_->size() || light.cols() != 3 || !light.allFinite())
    throw Error("lattice rotation: the basis's projection gave the wrong shape or NaN/Inf");
  return light;
}

}  // namespace prt
