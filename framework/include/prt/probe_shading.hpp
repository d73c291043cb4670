// Shading points (a moving object's vertices, or any surface) from the
// light a probe grid received: the 8 probes around each point, weighted
// trilinearly, with or without the leak control (docs/receivers.md).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "prt/basis.hpp"
#include "prt/mesh.hpp"
#include "prt/receivers.hpp"
#include "prt/transport.hpp"

namespace prt {

// The Lambertian lobe of each normal in the basis: row v is
// c_i = (1/pi) int b_i(w) max(0, n_v . w) dw, so that the exit radiance
// (albedo 1) of a point under incident light e is c . e. By quadrature on
// `set` (a sphere rule); v x n.
Eigen::MatrixXd cosine_lobes(const Basis& basis, const std::vector<Eigen::Vector3f>& normals,
                             const DirectionSet& set);

enum class ProbeInterpolation {
  trilinear,   // the 8 probes' trilinear weights, invalid probes included
  visibility,  // leak control: the point moves normal_bias spacings along its
               // normal (less where a surface is nearer; up to 3 rays);
               // invalid probes and probes it cannot see (a ray to the
               // probe is blocked) drop out, the rest renormalised
};

struct ProbeLookup {
  ProbeInterpolation interpolation = ProbeInterpolation::visibility;
  float normal_bias = 0.25f;  // in spacings
};

struct ProbeShading {
  Eigen::MatrixX3f radiance;  // v x 3, albedo 1
  // Leak control: points that saw none of their valid probes and fell back
  // to the valid ones in front of their surface (else all valid ones, else
  // every valid corner of their cell equally); points with no valid probe
  // among their cell's corners (black).
  std::size_t unseen = 0, no_valid_probe = 0;
  std::uint64_t rays_cast = 0;
};

// Which probes each point takes light from, and how much: the part of the
// shading that depends on where the points are, not on the light (a
// viewer keeps it while the light turns). Weights sum to 1, or to 0 where
// no valid probe is around.
struct ProbeWeights {
  std::vector<std::array<std::uint32_t, 8>> probes;
  std::vector<std::array<float, 8>> weights;
  std::size_t unseen = 0, no_valid_probe = 0;  // as ProbeShading's
  std::uint64_t rays_cast = 0;
};
ProbeWeights probe_weights(const Mesh& points, const ProbeGrid& grid,
                           const std::vector<std::uint8_t>& valid, const RayCaster* caster,
                           const ProbeLookup& lookup);
// Radiance (albedo 1) of the weighted points under the probes' incident light.
Eigen::MatrixX3f shade_with(const ProbeWeights& weights, const Eigen::MatrixXd& lobes,
                            const std::vector<Eigen::MatrixX3d>& incident);

// Both: `incident`: one n x 3 per probe (incident_light); `lobes`: one row
// per vertex of `points` (cosine_lobes of its normals); `caster`: the scene
// the visibility rays test (needed for ProbeInterpolation::visibility).
ProbeShading shade_from_probes(const Mesh& points, const ProbeGrid& grid,
                               const std::vector<std::uint8_t>& valid,
                               const std::vector<Eigen::MatrixX3d>& incident,
                               const Eigen::MatrixXd& lobes, const RayCaster* caster,
                               const ProbeLookup& lookup);

}  // namespace prt
