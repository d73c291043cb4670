#include "cpca_state.hpp"

#include <string>

#include "kept_on_ranks.hpp"

namespace prt::clustering {

namespace {

std::string labels_part(const char* what, int sequence, const Shard& shard) {
  return std::string("cpca.") + what + "." + std::to_string(sequence % 2) + ".rows-" +
         std::to_string(shard.first) + "-" + std::to_string(shard.last);
}

void save_labels(const PartKeeper& store, const char* what, int sequence, const Shard& shard,
                 const std::vector<std::int32_t>& labels) {
  std::vector<std::int32_t> part;
  part.reserve(labels.size() + 1);
  part.push_back(sequence);
  part.insert(part.end(), labels.begin(), labels.end());
  store.save(labels_part(what, sequence, shard), part);
}

std::optional<std::vector<std::int32_t>> load_labels(const PartKeeper& store, const char* what,
                                                     int sequence, const Shard& shard,
                                                     Eigen::Index rows, int k) {
  const std::string name = labels_part(what, sequence, shard);
  if (!store.has(name)) return std::nullopt;
  const std::vector<std::int32_t> part = store.load_ints(name);
  if (Eigen::Index(part.size()) != rows + 1 || part[0] != sequence) return std::nullopt;
  for (std::size_t p = 1; p < part.size(); ++p)
    if (part[p] < -1 || part[p] >= k) return std::nullopt;
  return std::vector<std::int32_t>(part.begin() + 1, part.end());
}

void save_models(const PartKeeper& store, const CpcaState& s) {
  // Figures, then per model: its direction count, mean, directions and eigenvalues.
  std::vector<double> v{double(s.phase), double(s.component), double(s.iteration),
                        double(s.sequence), double(s.models.size())};
  for (const ClusterModel& m : s.models) {
    v.push_back(double(m.basis.rows()));
    v.push_back(double(m.mean.size()));
    v.insert(v.end(), m.mean.data(), m.mean.data() + m.mean.size());
    v.insert(v.end(), m.basis.data(), m.basis.data() + m.basis.size());
    v.insert(v.end(), m.eigenvalues.data(), m.eigenvalues.data() + m.eigenvalues.size());
  }
  store.save("cpca.state", Eigen::MatrixXd(Eigen::Map<const Eigen::MatrixXd>(
                               v.data(), static_cast<Eigen::Index>(v.size()), 1)));
}

}  // namespace

bool keep_cpca_state(const PartKeeper& store, const Rows& rows, const CpcaState& s) {
  return keep_on_ranks(
      rows, "CPCA",
      [&] {
        save_labels(store, "labels", s.sequence, rows.shard, s.labels);
        save_labels(store, "fitted", s.sequence, rows.shard, s.fitted_labels);
      },
      [&] { save_models(store, s); });
}

std::optional<CpcaState> kept_cpca_state(const PartKeeper& store, const Rows& rows, int k) {
  const Eigen::Index n = rows.cols();
  if (!store.has("cpca.state")) return std::nullopt;
  const Eigen::MatrixXd part = store.load_doubles("cpca.state");
  if (part.cols() != 1 || part.rows() < 5) return std::nullopt;
  const double* v = part.data();
  const Eigen::Index size = part.rows();
  CpcaState s;
  s.phase = static_cast<int>(v[0]);
  s.component = static_cast<int>(v[1]);
  s.iteration = static_cast<int>(v[2]);
  s.sequence = static_cast<int>(v[3]);
  if (static_cast<int>(v[4]) != k || (s.phase != 0 && s.phase != 1)) return std::nullopt;
  Eigen::Index at = 5;
  for (int j = 0; j < k; ++j) {
    if (at + 2 > size) return std::nullopt;
    const Eigen::Index r = static_cast<Eigen::Index>(v[at]), width = Eigen::Index(v[at + 1]);
    at += 2;
    if (width != n || r < 0 || r > n || at + n + r * n + r > size) return std::nullopt;
    ClusterModel m;
    m.mean = Eigen::Map<const Eigen::RowVectorXd>(v + at, n);
    m.basis = Eigen::Map<const RowMatrixXd>(v + at + n, r, n);
    m.eigenvalues = Eigen::Map<const Eigen::VectorXd>(v + at + n + r * n, r);
    at += n + r * n + r;
    s.models.push_back(std::move(m));
  }
  if (at != size) return std::nullopt;
  auto labels = load_labels(store, "labels", s.sequence, rows.shard, rows.local(), k);
  auto fitted = load_labels(store, "fitted", s.sequence, rows.shard, rows.local(), k);
  if (!labels || !fitted) return std::nullopt;
  s.labels = std::move(*labels);
  s.fitted_labels = std::move(*fitted);
  return s;
}

}  // namespace prt::clustering
