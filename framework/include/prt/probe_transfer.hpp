// Probe transfer: at each probe of a grid, the operator that maps distant
// light (coefficients l in a sphere basis B) to the light arriving at the
// probe from every direction, shadowed by the scene, in a sphere basis E
// (the incident basis; E = B by default): e_p = T_p l, with
// T_p = P_E^T diag(V_p) B (P_E the incident basis's projection matrix on
// the direction set, B the light basis's values there, V_p the probe's
// visibility). An n_E x n_B matrix, like glossy transfer's N_r x N_i.
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
  // probes x n_E n_B, kind "incident", exit_rows n_E: T_p row-major (row i
  // is incident coefficient i); zero for an invalid probe.
  TransferSignal transfer;
  std::vector<std::uint8_t> valid;  // 0: inside geometry (back faces seen)
  std::uint64_t rays_cast = 0;
};

// `scene` is the geometry `caster` traces. A probe is invalid when more than
// `invalid_fraction` of its rays hit back faces (it sits inside a closed
// object). Unshadowed (`shadowed` false): V = 1 and no rays. Only probes
// [first, last) (a slab of a checkpointed or distributed bake): the
// result's rows and flags are theirs. Multithreaded; the result does not
// depend on the thread count or on the range.
ProbeTransfer probe_transfer(const RayCaster& caster, const Mesh& scene, const ProbeGrid& grid,
                             const DirectionSet& set, const Basis& light_basis,
                             const Basis& incident_basis, double invalid_fraction, bool shadowed,
                             Progress* progress, std::size_t first = 0,
                             std::size_t last = static_cast<std::size_t>(-1));

// The light arriving at each probe (n_E x 3 per probe: e_p = T_p l) from a
// probe transfer's rows in any encoding; `light` is n_B x 3.
std::vector<Eigen::MatrixX3d> incident_light(const CompressedTransfer& transfer, int incident_size,
                                             const Eigen::MatrixX3d& light);

}  // namespace prt
