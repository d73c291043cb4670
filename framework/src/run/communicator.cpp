#include "prt/communicator.hpp"

#include <cstring>

#include "prt/error.hpp"

namespace prt {

namespace {

class SoloCommunicator final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void barrier() const override {}
  std::vector<std::vector<char>> allgather(const std::vector<char>& mine) const override {
    return {mine};
  }
  std::vector<std::vector<char>> gather(const std::vector<char>& mine, int) const override {
    return {mine};
  }
  void broadcast(std::vector<char>&, int) const override {}
};

}  // namespace

const Communicator& solo() {
  static const SoloCommunicator instance;
  return instance;
}

Shard shard_of(Eigen::Index total, int rank, int ranks) {
  if (ranks < 1 || rank < 0 || rank >= ranks) throw Error("shard_of: rank out of range");
  const Eigen::Index segments = (total + kSegmentRows - 1) / kSegmentRows;
  const Eigen::Index first_segment = segments * rank / ranks,
                     last_segment = segments * (rank + 1) / ranks;
  return {std::min(total, first_segment * kSegmentRows),
          std::min(total, last_segment * kSegmentRows), total};
}

std::vector<char> to_bytes(const std::vector<double>& values) {
  std::vector<char> bytes(values.size() * sizeof(double));
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

std::vector<double> to_doubles(const std::vector<char>& bytes) {
  if (bytes.size() % sizeof(double) != 0) throw Error("communicator: a message of odd length");
  std::vector<double> values(bytes.size() / sizeof(double));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
  return values;
}

std::vector<std::vector<double>> allgather(const Communicator& comm,
                                           const std::vector<double>& values) {
  std::vector<std::vector<double>> out;
  for (const auto& bytes : comm.allgather(to_bytes(values))) out.push_back(to_doubles(bytes));
  return out;
}

void allreduce_min_max(const Communicator& comm, Eigen::RowVectorXd& min, Eigen::RowVectorXd& max) {
  if (comm.size() == 1) return;
  std::vector<double> mine(min.data(), min.data() + min.size());
  mine.insert(mine.end(), max.data(), max.data() + max.size());
  const auto all = allgather(comm, mine);
  const Eigen::Index n = min.size();
  for (const auto& other : all) {
    if (other.size() != std::size_t(2 * n)) throw Error("communicator: ranks disagree on a size");
    for (Eigen::Index i = 0; i < n; ++i) {
      min[i] = std::min(min[i], other[std::size_t(i)]);
      max[i] = std::max(max[i], other[std::size_t(n + i)]);
    }
  }
}

std::pair<double, std::int64_t> allreduce_argmax(const Communicator& comm, double value,
                                                 std::int64_t index) {
  if (comm.size() == 1) return {value, index};
  std::pair<double, std::int64_t> best{0, -1};
  for (const auto& other : allgather(comm, {value, double(index)})) {
    const auto i = static_cast<std::int64_t>(other[1]);
    if (i < 0) continue;
    if (best.second < 0 || other[0] > best.first || (other[0] == best.first && i < best.second))
      best = {other[0], i};
  }
  return best;
}

}  // namespace prt
