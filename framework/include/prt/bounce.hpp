// One bounce of light over a mesh as a kernel (diffuse and glossy
// inter-reflection give one): it maps the transfer of the previous bounce to
// the transfer of the light it sends on, for a range of rows. How the
// bounces are iterated, and kept for a resumed run, is the run layer's
// (prt/bounce_passes.hpp).
#pragma once
#include <functional>
#include <vector>

#include "prt/transfer.hpp"

namespace prt {

// The rows [first, last) of the light `previous` sends on.
using BounceFunction =
    std::function<MatrixXfRow(const MatrixXfRow& previous, std::size_t first, std::size_t last)>;

struct BouncedTransfer {
  MatrixXfRow total;                 // direct + every bounce
  std::vector<double> bounce_norms;  // Frobenius norm of each bounce's transfer
};

}  // namespace prt
