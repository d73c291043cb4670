// A transfer too large for the memory budget (issue 15): its rows are written
// to a file as they are computed and read back through a read-only mapping.
// Compressors read it in passes; each pass hands back the rows it is done
// with (release), so the pages it read leave the process (they stay in the
// page cache, which the kernel may reclaim) and its resident memory holds
// one block of rows per thread, not the signal.
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <memory>

#include "prt/transfer.hpp"

namespace prt {

class RowFile final : public OutOfCoreRows {
 public:
  // An unnamed rows x cols float file in `folder` (removed from the folder
  // at once: it lives as long as this object, and a killed process leaves
  // nothing behind). Throws prt::Error when the folder cannot hold it.
  static std::shared_ptr<RowFile> create(const std::filesystem::path& folder, Eigen::Index rows,
                                         Eigen::Index cols);
  ~RowFile();
  RowFile(const RowFile&) = delete;
  RowFile& operator=(const RowFile&) = delete;

  // Writes `block` as rows [first, first + block.rows()). Before map().
  void write(Eigen::Index first, Eigen::Ref<const MatrixXfRow> block);
  // Maps the written rows (read only); write() is refused after it.
  void map();

  Eigen::Index rows() const override { return rows_; }
  const std::filesystem::path& folder() const override { return where_; }
  Eigen::Index cols() const override { return cols_; }
  Eigen::Map<const MatrixXfRow> matrix() const override;
  // Drops the resident pages that hold any of rows [first, last) (a page
  // shared with a neighbour is read again from the page cache if needed);
  // release_all() after a pass that read rows at random.
  void release(Eigen::Index first, Eigen::Index last) const override;

 private:
  RowFile(int fd, Eigen::Index rows, Eigen::Index cols, std::filesystem::path where);
  int fd_ = -1;
  Eigen::Index rows_ = 0, cols_ = 0;
  std::filesystem::path where_;  // for messages
  void* mapping_ = nullptr;
  std::size_t bytes_ = 0;
};

}  // namespace prt
