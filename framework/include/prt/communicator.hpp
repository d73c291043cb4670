// What a distributed run needs from its message passing, so that the
// framework does not link MPI: prt-mpi implements it over MPI, and a single
// process uses solo(). The run layer: algorithms see a RowParts
// (prt/row_parts.hpp, made by parts_over in prt/communicator_parts.hpp),
// never a communicator. Ranks hold shards of whole segments of rows
// (vertices); sums over rows go through segment_sum (segment_sum.hpp), whose
// fixed tree makes them bit-identical for any number of ranks.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "prt/row_parts.hpp"
#include "prt/row_ranges.hpp"

namespace prt {

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual void barrier() const = 0;
  // Every rank's bytes, in rank order, on every rank.
  virtual std::vector<std::vector<char>> allgather(const std::vector<char>& mine) const = 0;
  // Every rank's bytes on `root` (in rank order); empty elsewhere.
  virtual std::vector<std::vector<char>> gather(const std::vector<char>& mine, int root) const = 0;
  // root's bytes on every rank.
  virtual void broadcast(std::vector<char>& bytes, int root) const = 0;
};

// One process: rank 0 of 1.
const Communicator& solo();

// Typed helpers over a communicator.
// Each rank's values, in rank order, on every rank.
std::vector<std::vector<double>> allgather(const Communicator& comm,
                                           const std::vector<double>& values);
// Elementwise min and max over ranks (exact: order does not matter).
void allreduce_min_max(const Communicator& comm, Eigen::RowVectorXd& min, Eigen::RowVectorXd& max);
// The largest value over ranks; ties go to the lowest index. Returns the
// winning (value, global index) pair; index -1 when every rank had none.
std::pair<double, std::int64_t> allreduce_argmax(const Communicator& comm, double value,
                                                 std::int64_t index);

}  // namespace prt
