#include "prt/compressor.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <set>

#include "prt/log.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/row_blocks.hpp"
#include "prt/segment_sum.hpp"

namespace prt {

double average_overdraw(const Mesh& mesh, const std::vector<std::int32_t>& id) {
  if (mesh.triangles.empty()) return 0.0;
  double sum = 0;
  for (const auto& t : mesh.triangles) {
    const std::int32_t a = id[t[0]], b = id[t[1]], c = id[t[2]];
    sum += 1 + (b != a) + (c != a && c != b);
  }
  return sum / double(mesh.triangles.size());
}

std::vector<std::int32_t> supercluster_of_vertex(const CompressedTransfer& c) {
  if (c.supercluster_of_cluster.empty()) return c.cluster_of_vertex;
  std::vector<std::int32_t> out(c.cluster_of_vertex.size());
  for (std::size_t p = 0; p < out.size(); ++p)
    out[p] = c.supercluster_of_cluster[c.cluster_of_vertex[p]];
  return out;
}

void gather_rows(const Distribution& rows, CompressedTransfer& c) {
  if (rows.comm->size() == 1) return;
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
  const auto all = rows.comm->gather(mine, 0);
  if (rows.comm->rank() != 0) return;
  const Eigen::Index total = rows.shard.total, width = c.weights.cols();
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
  for (int r = 0; r < rows.comm->size(); ++r) {
    const Shard shard = shard_of(total, r, rows.comm->size());
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

std::vector<double> vertex_errors(const TransferSignal& signal,
                                  const CompressedTransfer& compressed,
                                  const RenderedMetric* metric) {
  std::vector<double> errors(std::size_t(signal.vertices()));
  const auto rows = signal.rows();
  for_each_row_block(Eigen::Index(0), signal.vertices(), Eigen::Index(4096),
                     [&](Eigen::Index begin, Eigen::Index end) {
                       Eigen::RowVectorXf row(signal.dimension());
                       Eigen::MatrixXd difference(1, metric ? signal.dimension() : 0);
                       for (Eigen::Index p = begin; p < end; ++p) {
                         compressed.decode_row(p, row);
                         if (!metric) {  // coefficient space: the sum as it always was
                           errors[std::size_t(p)] =
                               (rows.row(p).cast<double>() - row.cast<double>()).squaredNorm();
                           continue;
                         }
                         difference = rows.row(p).cast<double>() - row.cast<double>();
                         metric->whiten_rows(difference, signal.exit_rows);
                         errors[std::size_t(p)] = difference.squaredNorm();
                       }
                       signal.release(begin, end);
                     });
  return errors;
}

CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                          const Mesh* mesh, double encode_seconds, const Distribution& where,
                          const RenderedMetric* metric) {
  CompressionReport r;
  if (metric && metric->identity()) metric = nullptr;
  r.rendered_metric = metric != nullptr;
  std::vector<double> errors = vertex_errors(signal, compressed, metric);
  r.squared_error = segment_sum_rows(where.shard, errors, *where.comm);
  if (where.comm->size() > 1) {  // every vertex's error on rank 0
    const auto all = where.comm->gather(to_bytes(errors), 0);
    errors.clear();
    for (const auto& part : all) {
      const auto values = to_doubles(part);
      errors.insert(errors.end(), values.begin(), values.end());
    }
    if (where.comm->rank() != 0) return r;
  }
  std::sort(errors.begin(), errors.end());
  auto percentile = [&](double q) {
    return errors.empty() ? 0.0
                          : errors[std::min(errors.size() - 1, std::size_t(q * errors.size()))];
  };
  r.vertex_error_p50 = percentile(0.5);
  r.vertex_error_p90 = percentile(0.9);
  r.vertex_error_p99 = percentile(0.99);
  r.vertex_error_max = errors.empty() ? 0.0 : errors.back();
  r.stored_floats = compressed.stored_floats();
  r.stored_bytes = 4 * r.stored_floats;
  r.encode_seconds = encode_seconds;
  r.clusters = static_cast<std::size_t>(compressed.clusters());
  r.statistics = compressed.statistics;
  if (mesh) {
    r.overdraw = average_overdraw(*mesh, compressed.cluster_of_vertex);
    r.supercluster_overdraw = average_overdraw(*mesh, supercluster_of_vertex(compressed));
  }
  return r;
}

std::string CompressionReport::json() const {
  nlohmann::ordered_json j;
  j["squared_error"] = squared_error;
  j["error_metric"] = rendered_metric ? "rendered" : "coefficients";
  j["vertex_squared_error"] = {{"p50", vertex_error_p50},
                               {"p90", vertex_error_p90},
                               {"p99", vertex_error_p99},
                               {"max", vertex_error_max}};
  j["stored_floats"] = stored_floats;
  j["stored_bytes"] = stored_bytes;
  j["encode_seconds"] = encode_seconds;
  j["clusters"] = clusters;
  j["overdraw"] = overdraw;
  j["supercluster_overdraw"] = supercluster_overdraw;
  j["statistics"] = nlohmann::ordered_json::object();
  for (const auto& [name, value] : statistics) j["statistics"][name] = value;
  return j.dump();
}

std::string CompressionReport::text() const {
  char buffer[768];
  std::snprintf(buffer, sizeof buffer,
                "SE %.6g%s  (per-vertex squared error p50 %.3g, p90 %.3g, p99 %.3g, max %.3g)\n"
                "storage %.0f floats = %.2f MB, %zu clusters, encode %.3f s, overdraw %.4f "
                "(superclusters %.4f)\n",
                squared_error, rendered_metric ? " in the rendered metric (function space)" : "",
                vertex_error_p50, vertex_error_p90, vertex_error_p99, vertex_error_max,
                stored_floats, stored_bytes / 1e6, clusters, encode_seconds, overdraw,
                supercluster_overdraw);
  std::string out = buffer;
  for (const auto& [name, value] : statistics) {
    std::snprintf(buffer, sizeof buffer, "  %s = %.6g\n", name.c_str(), value);
    out += buffer;
  }
  return out;
}

}  // namespace prt
