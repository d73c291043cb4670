// Probe transfer: at each probe of a grid, the operator that maps distant
// light (coefficients l in a sphere basis) to the light arriving at the
// probe from every direction, shadowed by the scene, in the same basis:
// e_p = T_p l, with T_p = P^T diag(V_p) B (P the basis's projection matrix
// on the direction set, B its values there, V_p the probe's visibility).
#pragma once
#include <cstdint>
#include <vector>

#include "prt/basis.hpp"
#include "prt/direction_set.hpp"
#include "prt/receivers.hpp"
#include "prt/transfer.hpp"
#include "prt/transport.hpp"

namespace prt {

class Progress;

struct ProbeTransfer {
  // probes x n^2, kind "incident", exit_rows n: T_p row-major (row i is the
  // incident coefficient i); zero for an invalid probe.
  TransferSignal transfer;
  std::vector<std::uint8_t> valid;  // 0: inside geometry (back faces seen)
  std::uint64_t rays_cast = 0;
};

// `scene` is the geometry `caster` traces. A probe is invalid when more than
// `invalid_fraction` of its rays hit back faces (it sits inside a closed
// object). Unshadowed (`shadowed` false): V = 1 and no rays. Multithreaded;
// the result does not depend on the thread count.
ProbeTransfer probe_transfer(const RayCaster& caster, const Mesh& scene, const ProbeGrid& grid,
                             const DirectionSet& set, const Basis& basis, double invalid_fraction,
                             bool shadowed, Progress* progress);

// The light arriving at each probe (n x 3 per probe: e_p = T_p l) from a
// probe transfer's rows in any encoding.
std::vector<Eigen::MatrixX3d> incident_light(const CompressedTransfer& transfer, int basis_size,
                                             const Eigen::MatrixX3d& light);

}  // namespace prt
