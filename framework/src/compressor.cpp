#include "prt/compressor.hpp"

#include <cstdio>
#include <cstring>

#include "prt/log.hpp"

namespace prt {

void gather_rows(const Distribution& where, CompressedTransfer& c) {
  if (!where.distributed()) return;
  const RowParts& parts = *where.parts;
  // One message: ids, then weights, then sparse indices, as raw bytes.
  std::vector<char> mine;
  // Every rank says whether its rows are sparse (a rank without rows has no
  // sparse indices to show it).
  const std::int32_t sparse_here = c.sparse() ? 1 : 0;
  auto put = [&](const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    mine.insert(mine.end(), p, p + size);
  };
  put(&sparse_here, sizeof sparse_here);
  put(c.cluster_of_vertex.data(), c.cluster_of_vertex.size() * sizeof(std::int32_t));
  put(c.weights.data(), std::size_t(c.weights.size()) * sizeof(float));
  put(c.weight_index.data(), c.weight_index.size() * sizeof(std::int32_t));
  const auto all = parts.gather(mine, 0);
  if (!parts.first()) return;
  const Eigen::Index total = parts.shard().total, width = c.weights.cols();
  bool sparse = false;
  for (const auto& message : all) {
    std::int32_t flag = 0;
    if (message.size() < sizeof flag) throw Error("compressed rows: an empty message");
    std::memcpy(&flag, message.data(), sizeof flag);
    sparse = sparse || flag != 0;
  }
  c.cluster_of_vertex.resize(std::size_t(total));
  c.weights.resize(total, width);
  if (sparse) c.weight_index.resize(std::size_t(total * width));
  for (int r = 0; r < parts.count(); ++r) {
    const Shard shard = parts.shard_of(r);
    const std::size_t count = std::size_t(shard.rows());
    const std::size_t expected = sizeof(std::int32_t) + count * sizeof(std::int32_t) +
                                 count * std::size_t(width) * sizeof(float) +
                                 (sparse ? count * std::size_t(width) * sizeof(std::int32_t) : 0);
    if (all[std::size_t(r)].size() != expected)
      throw Error("compressed rows: rank " + std::to_string(r) +
                  " sent compressed rows of the wrong size");
    const char* at = all[std::size_t(r)].data() + sizeof(std::int32_t);
    std::memcpy(&c.cluster_of_vertex[std::size_t(shard.first)], at, count * sizeof(std::int32_t));
    at += count * sizeof(std::int32_t);
    if (width) std::memcpy(c.weights.row(shard.first).data(), at, count * width * sizeof(float));
    at += count * std::size_t(width) * sizeof(float);
    if (sparse)
      std::memcpy(&c.weight_index[std::size_t(shard.first * width)], at,
                  count * std::size_t(width) * sizeof(std::int32_t));
  }
}

const TransferSignal& readable_signal(const Compressor& compressor, const std::string& name,
                                      const TransferSignal& signal,
                                      std::optional<TransferSignal>& loaded) {
  if (!signal.on_disk() || compressor.reads_rows_from_file()) return signal;
  char size[32];
  std::snprintf(size, sizeof size, "%.1f GB",
                double(signal.vertices()) * double(signal.dimension()) * 4 / 1e9);
  log_warning("compressor \"" + name + "\" reads the transfer from memory only: its " + size +
              " are loaded, beyond the memory budget");
  loaded = signal.loaded();
  return *loaded;
}

}  // namespace prt
