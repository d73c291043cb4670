// What an algorithm over rows (a basis fit, LBG, CPCA, a product summed over
// vertices) is handed by the run that calls it: which rows it holds and the
// few steps that combine the parts of a run. One process is a single part;
// prt-mpi makes a part per rank. The algorithm never learns which: it sums,
// gathers and picks through this interface, and the run layer implements it
// (prt/communicator_parts.hpp). Sums add per-segment partials along a fixed
// tree, so a result has the same bits for any number of parts or threads.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "prt/row_ranges.hpp"

namespace prt {

// partial(segment) returns the segment's vector (all of one length, or empty
// for zero); it is called only for this part's segments, possibly in
// parallel.
using SegmentPartial = std::function<std::vector<double>(Eigen::Index segment)>;
// Blocks keyed by an id (e.g. one scatter matrix per cluster): a segment
// returns the blocks of the ids it touches; absent ids count as zero.
using Blocks = std::map<std::int64_t, std::vector<double>>;
using SegmentBlocks = std::function<Blocks(Eigen::Index segment)>;

class RowParts {
 public:
  virtual ~RowParts() = default;
  // This part's index and the number of parts.
  virtual int index() const = 0;
  virtual int count() const = 0;
  // The rows this part holds, of the whole signal's shard().total.
  virtual Shard shard() const = 0;

  // Sums over every part's segments; the result is on every part.
  virtual std::vector<double> sum(const SegmentPartial& partial) const = 0;
  virtual Blocks sum_blocks(const SegmentBlocks& partial) const = 0;
  // The sum of one value per row of shard() (per_row[0] is its first row).
  virtual double sum_rows(const std::vector<double>& per_row) const = 0;

  // Elementwise min and max over the parts (exact: order does not matter).
  virtual void min_max(Eigen::RowVectorXd& min, Eigen::RowVectorXd& max) const = 0;
  // The largest value over the parts; ties go to the lowest index. Returns
  // the winning (value, index) pair; index -1 when every part had none.
  virtual std::pair<double, std::int64_t> argmax(double value, std::int64_t index) const = 0;
  // Each part's values, in part order, on every part.
  virtual std::vector<std::vector<double>> allgather(const std::vector<double>& mine) const = 0;
  // Each part's bytes, in part order, on `root`; empty elsewhere.
  virtual std::vector<std::vector<char>> gather(const std::vector<char>& mine, int root) const = 0;
  // root's bytes on every part.
  virtual void broadcast(std::vector<char>& bytes, int root) const = 0;

  bool distributed() const { return count() > 1; }
  bool first() const { return index() == 0; }
  Shard shard_of(int part) const { return prt::shard_of(shard().total, part, count()); }
};

// One process holding all `rows` rows.
std::shared_ptr<const RowParts> single_part(Eigen::Index rows);

// Doubles as bytes and back, for gather and broadcast.
std::vector<char> to_bytes(const std::vector<double>& values);
std::vector<double> to_doubles(const std::vector<char>& bytes);

}  // namespace prt
