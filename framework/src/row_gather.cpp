#include "prt/row_gather.hpp"

#include <cstring>
#include <vector>

#include "prt/error.hpp"

namespace prt {

MatrixXfRow gather_float_rows(const RowParts& parts, Eigen::Ref<const MatrixXfRow> local,
                              const std::string& what) {
  const Eigen::Index cols = local.cols();
  const std::size_t bytes = std::size_t(local.size()) * sizeof(float);
  std::vector<char> mine(bytes);
  if (bytes > 0) std::memcpy(mine.data(), local.data(), bytes);
  const auto all = parts.gather(mine, 0);
  MatrixXfRow whole;
  if (!parts.first()) return whole;
  whole.resize(parts.shard().total, cols);
  char* at = reinterpret_cast<char*>(whole.data());
  for (int part = 0; part < parts.count(); ++part) {
    const std::vector<char>& theirs = all[std::size_t(part)];
    if (theirs.size() != std::size_t(parts.shard_of(part).rows() * cols) * sizeof(float))
      throw Error(what + ": part " + std::to_string(part) + " sent rows of the wrong size");
    if (!theirs.empty()) std::memcpy(at, theirs.data(), theirs.size());
    at += theirs.size();
  }
  return whole;
}

}  // namespace prt
