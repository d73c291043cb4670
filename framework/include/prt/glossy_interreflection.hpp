// Glossy inter-reflection (Sloan, Kautz, Snyder 2002 §5; Sloan 2003 §3):
// each pass gathers, at every vertex p, the light that arrives along the
// shadow pass's blocked rays. A ray along s that hits q brings q's exit
// radiance toward p, read from q's transfer of the previous pass:
//   r(s) = sum_c beta_c y_exit(F_c (-s))^T M_c^{b-1}        (1 x N_i)
// interpolated over the hit triangle's corners c (each in its own frame).
// That incident radiance, linear in the light, replaces b(s)^T V_p(s) in
// the direct glossy transfer:
//   M_p^b = a G R_M(F_p) sum_k w_k y_M(s_k) r(s_k)
// with a the bounce albedo (the grey tint of the material). Corners that see
// the ray from below their tangent plane send nothing.
#pragma once
#include <vector>

#include "prt/basis.hpp"
#include "prt/bounce.hpp"
#include "prt/direction_set.hpp"
#include "prt/frame.hpp"
#include "prt/glossy.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"
#include "prt/transport.hpp"

namespace prt {

class Progress;

// One pass: `previous` (v x N_r N_i glossy transfer) -> the transfer of the
// light it sends on (same shape), or of vertices [first, last) only.
MatrixXfRow glossy_bounce(const Mesh& mesh, const DirectionSet& directions, const HitLists& hits,
                          const MatrixXfRow& previous, const Basis& exit_basis,
                          const GlossyOperator& glossy, int light_size,
                          const std::vector<Frame>& frames, double albedo, std::size_t first = 0,
                          std::size_t last = static_cast<std::size_t>(-1));

// The same as the kernel that bounce_passes (prt/bounce_passes.hpp) iterates;
// it refers to its arguments, which must outlive it. Throws unless albedo is
// in [0, 1].
BounceFunction glossy_bounce_function(const Mesh& mesh, const DirectionSet& directions,
                                      const HitLists& hits, const Basis& exit_basis,
                                      const GlossyOperator& glossy, int light_size,
                                      const std::vector<Frame>& frames, double albedo);

}  // namespace prt
