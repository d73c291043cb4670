// Float rows of a signal split over the parts of a run, joined in row order
// on the first part (RowParts::gather, with each part's size checked): what
// a pass that needs every row in one place (reclassification, the exact
// form's means) is handed.
#pragma once
#include <string>

#include "prt/row_parts.hpp"
#include "prt/transfer.hpp"

namespace prt {

// `local` holds this part's rows (parts.shard()); the first part gets all
// parts.shard().total rows, the others an empty matrix. `what` names the rows
// in the error a part of the wrong size raises.
MatrixXfRow gather_float_rows(const RowParts& parts, Eigen::Ref<const MatrixXfRow> local,
                              const std::string& what);

}  // namespace prt
