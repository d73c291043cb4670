// Diffuse inter-reflection (Sloan, Kautz, Snyder 2002 §5; Chen 2005 §3.1):
// after the shadow pass, each bounce gathers the previous bounce's transfer
// from the front-face hit points of the rays the shadow pass already traced
// (barycentric interpolation of the hit triangle's vertices):
//   t_p^b = rho * sum_{blocked s_k} w_k max(n_p . s_k, 0) / pi * t_q(s_k)^{b-1}
// The transfer is linear in the light, so this works on the coefficients of
// any basis. rho < 1 makes every bounce smaller than the one before; each
// bounce is at most rho times the previous one.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "prt/bounce.hpp"
#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"
#include "prt/transport.hpp"

namespace prt {

class Progress;

// One bounce: `previous` (v x n) -> the light it sends to each vertex (v x n),
// or to vertices [first, last) only (a row each).
MatrixXfRow gather_bounce(const Mesh& mesh, const DirectionSet& directions, const HitLists& hits,
                          const MatrixXfRow& previous, double albedo, std::size_t first = 0,
                          std::size_t last = static_cast<std::size_t>(-1));

// The same as the kernel that bounce_passes (prt/bounce_passes.hpp) iterates;
// it refers to its arguments, which must outlive it. Throws unless albedo is
// in [0, 1].
BounceFunction diffuse_bounce(const Mesh& mesh, const DirectionSet& directions,
                              const HitLists& hits, double albedo);

// The ground truth's bounces, independent of any basis and of the bake's
// directions: per vertex `samples` fresh cosine-distributed rays gather the
// previous bounce's radiance (v x 3) from their front-face hits.
Eigen::MatrixX3f ground_truth_bounces(const Mesh& mesh, const Eigen::MatrixX3f& direct, int bounces,
                                      double albedo, int samples, std::uint64_t seed,
                                      Progress* progress);

}  // namespace prt
