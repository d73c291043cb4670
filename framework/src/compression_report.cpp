// What an encoding costs and how far it is from the signal (Sloan et al.
// 2003, section 4: the squared error SE summed over vertices, and the
// storage m_p n' + m_c (n' + 1) n), measured the same way for every
// compressor, in the rendered metric when the bases are not orthonormal.
#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "prt/compressor.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/row_blocks.hpp"

namespace prt {

namespace {

// Each vertex's squared error |F(t_p - t~_p)|^2 (F the rendered metric's
// whitening, identity without one) and, when `energies` is given, |F t_p|^2
// in the same pass over the rows (an out-of-core signal is read once).
std::vector<double> row_errors(const TransferSignal& signal, const CompressedTransfer& compressed,
                               const RenderedMetric* metric, std::vector<double>* energies) {
  std::vector<double> errors(std::size_t(signal.vertices()));
  if (energies) energies->assign(errors.size(), 0.0);
  const auto rows = signal.rows();
  for_each_row_block(Eigen::Index(0), signal.vertices(), Eigen::Index(4096),
                     [&](Eigen::Index begin, Eigen::Index end) {
                       Eigen::RowVectorXf row(signal.dimension());
                       Eigen::MatrixXd difference(1, metric ? signal.dimension() : 0);
                       Eigen::MatrixXd exact = difference;
                       for (Eigen::Index p = begin; p < end; ++p) {
                         compressed.decode_row(p, row);
                         if (!metric) {  // coefficient space: the sum as it always was
                           errors[std::size_t(p)] =
                               (rows.row(p).cast<double>() - row.cast<double>()).squaredNorm();
                           if (energies)
                             (*energies)[std::size_t(p)] = rows.row(p).cast<double>().squaredNorm();
                           continue;
                         }
                         difference = rows.row(p).cast<double>() - row.cast<double>();
                         metric->whiten_rows(difference, signal.exit_rows);
                         errors[std::size_t(p)] = difference.squaredNorm();
                         if (!energies) continue;
                         exact = rows.row(p).cast<double>();
                         metric->whiten_rows(exact, signal.exit_rows);
                         (*energies)[std::size_t(p)] = exact.squaredNorm();
                       }
                       signal.release(begin, end);
                     });
  return errors;
}

}  // namespace

std::vector<double> vertex_errors(const TransferSignal& signal,
                                  const CompressedTransfer& compressed,
                                  const RenderedMetric* metric) {
  return row_errors(signal, compressed, metric, nullptr);
}

CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                          const Mesh* mesh, double encode_seconds, const Distribution& where,
                          const RenderedMetric* metric) {
  CompressionReport r;
  if (metric && metric->identity()) metric = nullptr;
  r.rendered_metric = metric != nullptr;
  std::vector<double> energies;
  std::vector<double> errors = row_errors(signal, compressed, metric, &energies);
  const auto parts = where.row_parts(signal.vertices());
  r.squared_error = parts->sum_rows(errors);
  r.signal_energy = parts->sum_rows(energies);
  if (parts->distributed()) {  // every vertex's error on the first part
    const auto all = parts->gather(to_bytes(errors), 0);
    errors.clear();
    for (const auto& part : all) {
      const auto values = to_doubles(part);
      errors.insert(errors.end(), values.begin(), values.end());
    }
    if (!parts->first()) return r;
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
  if (compressed.clusters() > 1) r.index_bytes = 4.0 * double(compressed.vertices());
  r.index_bytes += 4.0 * double(compressed.supercluster_of_cluster.size());
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
  j["signal_energy"] = signal_energy;
  j["relative_squared_error"] = relative_squared_error();
  j["error_metric"] = rendered_metric ? "rendered" : "coefficients";
  j["vertex_squared_error"] = {{"p50", vertex_error_p50},
                               {"p90", vertex_error_p90},
                               {"p99", vertex_error_p99},
                               {"max", vertex_error_max}};
  j["stored_floats"] = stored_floats;
  j["stored_bytes"] = stored_bytes;
  j["index_bytes"] = index_bytes;
  j["total_bytes"] = total_bytes();
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
                "SE %.6g%s, %.4g of the signal's energy  (per-vertex squared error p50 %.3g, "
                "p90 %.3g, p99 %.3g, max %.3g)\n"
                "storage %.0f floats = %.2f MB + %.2f MB of cluster indices = %.2f MB, %zu "
                "clusters, encode %.3f s, overdraw %.4f (superclusters %.4f)\n",
                squared_error, rendered_metric ? " in the rendered metric (function space)" : "",
                relative_squared_error(), vertex_error_p50, vertex_error_p90, vertex_error_p99,
                vertex_error_max, stored_floats, stored_bytes / 1e6, index_bytes / 1e6,
                total_bytes() / 1e6, clusters, encode_seconds, overdraw, supercluster_overdraw);
  std::string out = buffer;
  for (const auto& [name, value] : statistics) {
    std::snprintf(buffer, sizeof buffer, "  %s = %.6g\n", name.c_str(), value);
    out += buffer;
  }
  return out;
}

}  // namespace prt
