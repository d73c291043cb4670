#include "prt/communicator_parts.hpp"

#include "prt/error.hpp"
#include "prt/segment_sum.hpp"

namespace prt {

namespace {

class CommunicatorParts final : public RowParts {
 public:
  CommunicatorParts(const Communicator& comm, const Shard& shard) : comm_(comm), shard_(shard) {}

  int index() const override { return comm_.rank(); }
  int count() const override { return comm_.size(); }
  Shard shard() const override { return shard_; }

  std::vector<double> sum(const SegmentPartial& partial) const override {
    return segment_sum(shard_, partial, comm_);
  }
  Blocks sum_blocks(const SegmentBlocks& partial) const override {
    return segment_sum_blocks(shard_, partial, comm_);
  }
  double sum_rows(const std::vector<double>& per_row) const override {
    return segment_sum_rows(shard_, per_row, comm_);
  }
  void min_max(Eigen::RowVectorXd& min, Eigen::RowVectorXd& max) const override {
    allreduce_min_max(comm_, min, max);
  }
  std::pair<double, std::int64_t> argmax(double value, std::int64_t index) const override {
    return allreduce_argmax(comm_, value, index);
  }
  std::vector<std::vector<double>> allgather(const std::vector<double>& mine) const override {
    return prt::allgather(comm_, mine);
  }
  std::vector<std::vector<char>> gather(const std::vector<char>& mine, int root) const override {
    return comm_.gather(mine, root);
  }
  void broadcast(std::vector<char>& bytes, int root) const override {
    comm_.broadcast(bytes, root);
  }

 private:
  const Communicator& comm_;
  Shard shard_;
};

}  // namespace

std::shared_ptr<const RowParts> parts_over(const Communicator& comm, const Shard& shard) {
  if (shard.first < 0 || shard.first > shard.last || shard.last > shard.total)
    throw Error("parts_over: rows [" + std::to_string(shard.first) + ", " +
                std::to_string(shard.last) + ") are not within " + std::to_string(shard.total));
  return std::make_shared<CommunicatorParts>(comm, shard);
}

std::shared_ptr<const RowParts> single_part(Eigen::Index rows) {
  return parts_over(solo(), whole(rows));
}

}  // namespace prt
