// The Monte Carlo ground truth that PRT is measured against: no basis, no
// compression, the environment sampled directly with ray-cast visibility.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

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
  const Eigen::Vector3d& tangent() const { return tangent_; }
  const Eigen::Vector3d& bitangent() const { return bitangent_; }

 private:
  Eigen::Vector3d normal_, tangent_, bitangent_;
};

// Ground truth: per-vertex exit radiance (v x 3) for albedo 1, by Monte Carlo
// over the environment with ray-cast visibility; no basis involved.
// Vertices are taken in blocks of kSharedBlock along a Morton curve, and a
// block shares one stratified sample set (SharedSamples): under a constant
// map cosine-weighted directions in each vertex's frame (exact on a convex
// object), under a real map uniform-sphere and map-importance directions
// combined by the balance heuristic, drawn and looked up in the map once per
// block. Each vertex traces those above its tangent plane: nearby origins
// along the same directions, coherent rays as the bake's. A block's error is
// correlated; batches with other seeds are independent.
// For glossy materials `reflectance` (optional) gives pi * rho(in, out) at a
// vertex for a world light direction, which replaces albedo 1.
class Environment;
class EnvironmentSampler;
using Reflectance = std::function<double(std::size_t vertex, const Eigen::Vector3d& light)>;

struct GroundTruthEstimate {
  Eigen::MatrixX3f radiance;  // v x 3
  std::uint64_t rays = 0;     // occlusion rays traced
};
GroundTruthEstimate ground_truth_estimate(const Mesh& mesh, const Environment& environment,
                                          int samples, std::uint64_t seed, Progress* progress,
                                          const Reflectance& reflectance = nullptr);
// Its radiance alone.
Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
                                       int samples, std::uint64_t seed, Progress* progress,
                                       const Reflectance& reflectance = nullptr);

// Vertices that share one sample set.
constexpr std::size_t kSharedBlock = 256;

// One block's samples. `local`: directions in each vertex's frame (x, y
// tangent, z normal), each carrying `weighted` = L / N (the cosine cancels
// its density); otherwise world directions, each carrying
// L / (pi (N_sphere p_sphere + N_map p_map)), to be multiplied by the
// vertex's cosine.
struct SharedSamples {
  bool local = false;
  std::vector<Eigen::Vector3f> directions;
  std::vector<Eigen::Vector3d> weighted;
};
// The set of block `block` of a run with `seed`: side^2 strata per strategy
// (a null sampler: the cosine strategy alone, for a constant map).
SharedSamples draw_shared_samples(const Environment& environment, const EnvironmentSampler* sampler,
                                  int side, std::uint64_t seed, std::size_t block);

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
