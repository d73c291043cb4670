// A signal mapped block by block, wherever its rows live (memory or a file).
#include "prt/error.hpp"
#include "prt/row_blocks.hpp"
#include "prt/row_file.hpp"

namespace prt {

TransferSignal map_row_blocks(const TransferSignal& signal, Eigen::Index block_rows,
                              const RowBlockMap& map) {
  TransferSignal out = signal;
  out.file.reset();
  const Eigen::Index rows = signal.vertices(), cols = signal.dimension();
  const auto source = signal.rows();
  std::shared_ptr<RowFile> file;
  if (signal.on_disk())
    file = RowFile::create(signal.file->folder(), rows, cols);
  else
    out.coefficients.resize(rows, cols);
  for_each_row_block(Eigen::Index(0), rows, block_rows, [&](Eigen::Index begin, Eigen::Index end) {
    const MatrixXfRow block = map(source.middleRows(begin, end - begin));
    if (block.rows() != end - begin || block.cols() != cols)
      throw Error("map_row_blocks: a block of " + std::to_string(end - begin) + " x " +
                  std::to_string(cols) + " rows came back " + std::to_string(block.rows()) + " x " +
                  std::to_string(block.cols()));
    if (file)
      file->write(begin, block);
    else
      out.coefficients.middleRows(begin, end - begin) = block;
    signal.release(begin, end);
  });
  if (file) {
    file->map();
    out.file = std::move(file);
  }
  return out;
}

}  // namespace prt
