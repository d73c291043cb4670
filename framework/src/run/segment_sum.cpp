#include "prt/segment_sum.hpp"

#include <tbb/parallel_invoke.h>

#include <cstring>
#include <map>
#include <string>

#include "prt/error.hpp"

namespace prt {

namespace {

using Vector = std::vector<double>;
using Node = std::pair<int, Eigen::Index>;  // level, index: segments [index << level, ...)

// left += right, an empty vector being zero.
void add_into(Vector& left, Vector&& right) {
  if (right.empty()) return;
  if (left.empty()) {
    left = std::move(right);
    return;
  }
  if (left.size() != right.size()) throw Error("segment_sum: partials of different lengths");
  for (std::size_t i = 0; i < left.size(); ++i) left[i] += right[i];
}

void add_into(Blocks& left, Blocks&& right) {
  for (auto& [id, values] : right) add_into(left[id], std::move(values));
}

void put(std::vector<char>& bytes, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  bytes.insert(bytes.end(), p, p + size);
}

void put(std::vector<char>& bytes, const Vector& values) {
  const std::int64_t count = static_cast<std::int64_t>(values.size());
  put(bytes, &count, sizeof count);
  put(bytes, values.data(), values.size() * sizeof(double));
}

void put(std::vector<char>& bytes, const Blocks& blocks) {
  const std::int64_t count = static_cast<std::int64_t>(blocks.size());
  put(bytes, &count, sizeof count);
  for (const auto& [id, values] : blocks) {
    put(bytes, &id, sizeof id);
    put(bytes, values);
  }
}

struct Reader {
  const std::vector<char>& bytes;
  std::size_t at = 0;
  void get(void* data, std::size_t size) {
    if (at + size > bytes.size()) throw Error("segment_sum: truncated message");
    if (size) std::memcpy(data, &bytes[at], size);
    at += size;
  }
  std::int64_t integer() {
    std::int64_t value = 0;
    get(&value, sizeof value);
    return value;
  }
  void read(Vector& values) {
    const std::int64_t count = integer();
    if (count < 0 || std::uint64_t(count) > (bytes.size() - at) / sizeof(double))
      throw Error("segment_sum: truncated message");
    values.resize(static_cast<std::size_t>(count));
    get(values.data(), values.size() * sizeof(double));
  }
  void read(Blocks& blocks) {
    for (std::int64_t n = integer(); n > 0; --n) {
      const std::int64_t id = integer();
      read(blocks[id]);
    }
  }
};

// A node's sum, its two halves in parallel near the top of the tree.
template <class Value, class Partial>
Value compute(int level, Eigen::Index index, Eigen::Index segments, const Partial& partial) {
  if ((index << level) >= segments) return {};
  if (level == 0) return partial(index);
  Value left, right;
  if (level >= 2) {
    tbb::parallel_invoke(
        [&] { left = compute<Value>(level - 1, 2 * index, segments, partial); },
        [&] { right = compute<Value>(level - 1, 2 * index + 1, segments, partial); });
  } else {
    left = compute<Value>(level - 1, 2 * index, segments, partial);
    right = compute<Value>(level - 1, 2 * index + 1, segments, partial);
  }
  add_into(left, std::move(right));
  return left;
}

// The tree's root from the nodes the ranks computed: the same additions, in
// the same order, as compute() of the root.
template <class Value>
Value evaluate(int level, Eigen::Index index, Eigen::Index segments, std::map<Node, Value>& known) {
  if ((index << level) >= segments) return {};
  if (auto it = known.find({level, index}); it != known.end()) return std::move(it->second);
  if (level == 0) throw Error("segment_sum: no rank computed segment " + std::to_string(index));
  Value left = evaluate(level - 1, 2 * index, segments, known);
  add_into(left, evaluate(level - 1, 2 * index + 1, segments, known));
  return left;
}

template <class Value, class Partial>
Value tree_sum(const Shard& shard, const Partial& partial, const Communicator& comm) {
  const Eigen::Index segments = (shard.total + kSegmentRows - 1) / kSegmentRows;
  if (segments == 0) return {};
  int top = 0;
  while ((Eigen::Index(1) << top) < segments) ++top;
  if (shard.first % kSegmentRows != 0 ||
      (shard.last % kSegmentRows != 0 && shard.last != shard.total))
    throw Error("segment_sum: a shard must hold whole segments");
  // The largest aligned subtrees inside this rank's segments.
  const Eigen::Index first = shard.first / kSegmentRows,
                     last = (shard.last + kSegmentRows - 1) / kSegmentRows;
  std::map<Node, Value> known;
  for (Eigen::Index i = first; i < last;) {
    int level = 0;
    while (level < top && i % (Eigen::Index(2) << level) == 0 &&
           i + (Eigen::Index(2) << level) <= last)
      ++level;
    known[{level, i >> level}] = compute<Value>(level, i >> level, segments, partial);
    i += Eigen::Index(1) << level;
  }
  if (comm.size() <= 1) return evaluate(top, 0, segments, known);
  // Rank 0 gathers the ranks' subtree roots, adds them as compute() of the
  // root would, and broadcasts the sum: each rank receives one root, not
  // every rank's subtrees (an allgather's traffic grew with the rank count).
  std::vector<char> mine;
  for (const auto& [node, value] : known) {
    const std::int64_t header[2] = {node.first, node.second};
    put(mine, header, sizeof header);
    put(mine, value);
  }
  known.clear();
  const std::vector<std::vector<char>> parts = comm.gather(mine, 0);
  // A first byte says whether rank 0 could add them; if not, every rank
  // throws its message (a failure on rank 0 alone would leave the others
  // waiting for the sum).
  std::vector<char> sum;
  if (comm.rank() == 0) {
    try {
      for (const auto& bytes : parts) {
        Reader reader{bytes};
        while (reader.at < bytes.size()) {
          const int level = static_cast<int>(reader.integer());
          const Eigen::Index index = reader.integer();
          reader.read(known[{level, index}]);
        }
      }
      sum.push_back(1);
      put(sum, evaluate(top, 0, segments, known));
    } catch (const std::exception& e) {
      const std::string message = e.what();
      sum.assign(1, 0);
      sum.insert(sum.end(), message.begin(), message.end());
    }
  }
  comm.broadcast(sum, 0);
  if (sum.empty()) throw Error("segment_sum: rank 0 sent no sum");
  if (sum[0] != 1) throw Error(std::string(sum.begin() + 1, sum.end()));
  Reader reader{sum, 1};
  Value root;
  reader.read(root);
  if (reader.at != sum.size()) throw Error("segment_sum: the broadcast sum has trailing bytes");
  return root;
}

}  // namespace

Vector segment_sum(const Shard& shard, const SegmentPartial& partial, const Communicator& comm) {
  return tree_sum<Vector>(shard, partial, comm);
}

double segment_sum_rows(const Shard& shard, const std::vector<double>& per_row,
                        const Communicator& comm) {
  const Vector total = segment_sum(
      shard,
      [&](Eigen::Index s) {
        double t = 0;
        for (Eigen::Index p = segment_begin(s); p < segment_end(s, shard.total); ++p)
          t += per_row[std::size_t(p - shard.first)];
        return Vector{t};
      },
      comm);
  return total.empty() ? 0.0 : total[0];
}

Blocks segment_sum_blocks(const Shard& shard, const SegmentBlocks& partial,
                          const Communicator& comm) {
  return tree_sum<Blocks>(shard, partial, comm);
}

}  // namespace prt
