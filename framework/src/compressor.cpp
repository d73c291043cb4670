#include "prt/compressor.hpp"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>

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

CompressionReport measure(const TransferSignal& signal, const CompressedTransfer& compressed,
                          const Mesh* mesh, double encode_seconds) {
  CompressionReport r;
  const MatrixXfRow decoded = compressed.decode();
  std::vector<double> errors(signal.vertices());
  for (Eigen::Index p = 0; p < signal.vertices(); ++p) {
    errors[p] =
        (signal.coefficients.row(p).cast<double>() - decoded.row(p).cast<double>()).squaredNorm();
    r.squared_error += errors[p];
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
                "SE %.6g  (per-vertex squared error p50 %.3g, p90 %.3g, p99 %.3g, max %.3g)\n"
                "storage %.0f floats = %.2f MB, %zu clusters, encode %.3f s, overdraw %.4f "
                "(superclusters %.4f)\n",
                squared_error, vertex_error_p50, vertex_error_p90, vertex_error_p99,
                vertex_error_max, stored_floats, stored_bytes / 1e6, clusters, encode_seconds,
                overdraw, supercluster_overdraw);
  std::string out = buffer;
  for (const auto& [name, value] : statistics) {
    std::snprintf(buffer, sizeof buffer, "  %s = %.6g\n", name.c_str(), value);
    out += buffer;
  }
  return out;
}

}  // namespace prt
