// The checks a bake's values get in the process that uses them, after the
// parse (bake_file_read.cpp): each value against its range and the fields
// against each other, so that nothing a crafted file says is used unchecked.
#pragma once
#include "prt/bake_file.hpp"

namespace prt {

// Throws prt::Error naming the first field that is out of range or that
// disagrees with another; completes the direct part's layout.
void check_bake_values(BakeData& data);

}  // namespace prt
