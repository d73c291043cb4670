// The Monte Carlo ground truth that PRT is measured against: no basis, no
// compression, the environment sampled directly with ray-cast visibility.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>

#include "prt/mesh.hpp"

namespace prt {

class Progress;

// Cosine-weighted directions about a unit normal: sample(u1, u2) maps the unit
// square to the hemisphere with density cos / pi (Malley's method). Shared by
// the ground truth's direct light and its bounces.
class CosineHemisphere {
 public:
  explicit CosineHemisphere(const Eigen::Vector3d& normal);
  Eigen::Vector3d sample(double u1, double u2) const;

 private:
  Eigen::Vector3d normal_, tangent_, bitangent_;
};

// Ground truth: per-vertex exit radiance (v x 3) for albedo 1, by Monte Carlo
// over the environment with cosine-weighted stratified samples and ray-cast
// visibility; no basis involved.
// For glossy materials `reflectance` (optional) gives pi * rho(in, out) at a
// vertex for a world light direction, which replaces albedo 1.
class Environment;
using Reflectance = std::function<double(std::size_t vertex, const Eigen::Vector3d& light)>;
Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
                                       int samples, std::uint64_t seed, Progress* progress,
                                       const Reflectance& reflectance = nullptr);

}  // namespace prt

namespace prt {

struct Brdf;

// The glossy ground truth's inter-reflected light, independent of any basis
// and of the bake's directions: per vertex `samples` paths (stratified
// cosine-weighted first directions) that hit the mesh and continue for up to
// `bounces` reflections, each hit point q shading with the BRDF in its own
// frame (interpolated normal) toward where the path came from, times the
// bounce albedo. At each hit, the environment's light is gathered by two
// strategies (cosine and the map's importance sampling) combined by the
// balance heuristic. Returns the radiance the bounces add toward each
// vertex's local view (v x 3, albedo 1); the direct light is
// ground_truth_radiance's.
Eigen::MatrixX3f ground_truth_glossy_bounces(const Mesh& mesh, const Environment& environment,
                                             const Brdf& brdf, const Eigen::MatrixXd& local_views,
                                             int bounces, double albedo, int samples,
                                             std::uint64_t seed, Progress* progress);

}  // namespace prt
