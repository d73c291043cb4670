// Cluster coherence: reclassification of boundary vertices and
// superclustering, both to lower overdraw (Sloan 2003 §5, Chen 2005 ch. 4).
#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <queue>
#include <set>

#include "prt/clustering.hpp"
#include "prt/error.hpp"

namespace prt::clustering {

namespace {

int distinct(std::int32_t a, std::int32_t b, std::int32_t c) {
  return 1 + (b != a) + (c != a && c != b);
}

struct Adjacency {
  std::vector<std::vector<std::uint32_t>> triangles_of;  // per vertex
  std::vector<std::vector<std::uint32_t>> neighbours;    // per vertex, sorted, unique
};

Adjacency adjacency(const Mesh& mesh) {
  Adjacency a;
  a.triangles_of.resize(mesh.vertex_count());
  a.neighbours.resize(mesh.vertex_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int i = 0; i < 3; ++i) {
      const auto v = mesh.triangles[t][i];
      a.triangles_of[v].push_back(static_cast<std::uint32_t>(t));
      a.neighbours[v].push_back(mesh.triangles[t][(i + 1) % 3]);
      a.neighbours[v].push_back(mesh.triangles[t][(i + 2) % 3]);
    }
  for (auto& n : a.neighbours) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return a;
}

// Squared error of row p approximated in cluster k of the compressed form
// (orthonormal representatives), in double.
double error_in(RowsRef x, Eigen::Index p, const CompressedTransfer& c, int k) {
  const Eigen::RowVectorXd d = x.row(p).cast<double>() - c.means.row(k).cast<double>();
  double e = d.squaredNorm();
  if (c.components_of(k) > 0)
    e -= (c.representatives[k].cast<double>() * d.transpose()).squaredNorm();
  return std::max(e, 0.0);
}

}  // namespace

std::size_t reclassify(RowsRef x, const Mesh& mesh, double error_budget,
                       CompressedTransfer& compressed,
                       const std::function<void(Eigen::Index, Eigen::Index)>& release) {
  // Sweeps hand back each 4,096 rows they are done with.
  const auto swept = [&](Eigen::Index p) {
    if (release && (p + 1) % 4096 == 0) release(p + 1 - 4096, p + 1);
  };
  if (static_cast<std::size_t>(x.rows()) != mesh.vertex_count())
    throw Error("reclassify: transfer rows do not match the mesh's vertices");
  auto& label = compressed.cluster_of_vertex;
  const Adjacency adj = adjacency(mesh);
  double total = 0;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    total += error_in(x, p, compressed, label[p]);
    swept(p);
  }
  const double budget = error_budget * total;

  struct Move {
    double priority;  // overdraw reduction per unit error increase
    int reduction;
    double increase;
    std::uint32_t vertex;
    std::int32_t target;
    std::uint32_t version;
    bool operator<(const Move& o) const { return priority < o.priority; }
  };
  std::vector<std::uint32_t> version(mesh.vertex_count(), 0);
  auto best_move = [&](std::uint32_t p) -> std::optional<Move> {
    std::set<std::int32_t> candidates;
    for (auto q : adj.neighbours[p])
      if (label[q] != label[p]) candidates.insert(label[q]);
    if (candidates.empty()) return std::nullopt;
    const double own = error_in(x, p, compressed, label[p]);
    std::optional<Move> best;
    for (std::int32_t target : candidates) {
      int reduction = 0;
      for (auto t : adj.triangles_of[p]) {
        std::array<std::int32_t, 3> ids{};
        for (int i = 0; i < 3; ++i) ids[i] = label[mesh.triangles[t][i]];
        const int before = distinct(ids[0], ids[1], ids[2]);
        for (int i = 0; i < 3; ++i)
          if (mesh.triangles[t][i] == p) ids[i] = target;
        reduction += before - distinct(ids[0], ids[1], ids[2]);
      }
      if (reduction <= 0) continue;
      const double increase = error_in(x, p, compressed, target) - own;
      const double priority =
          increase <= 0 ? std::numeric_limits<double>::infinity() : reduction / increase;
      if (!best || priority > best->priority)
        best = Move{priority, reduction, increase, p, target, version[p]};
    }
    return best;
  };

  std::priority_queue<Move> heap;
  for (std::uint32_t p = 0; p < mesh.vertex_count(); ++p) {
    if (auto m = best_move(p)) heap.push(*m);
    swept(p);
  }
  if (release) release(0, x.rows());
  double spent = 0;
  std::vector<std::uint8_t> moved(mesh.vertex_count(), 0);
  std::size_t moves = 0;
  while (!heap.empty()) {
    const Move m = heap.top();
    heap.pop();
    if (m.version != version[m.vertex]) continue;  // stale: re-evaluated since
    if (spent + m.increase > budget) continue;     // too costly; cheaper moves may remain
    spent += m.increase;
    label[m.vertex] = m.target;
    moved[m.vertex] = 1;
    ++moves;
    for (std::uint32_t q : adj.neighbours[m.vertex]) ++version[q];
    ++version[m.vertex];
    for (std::uint32_t q : adj.neighbours[m.vertex])
      if (auto next = best_move(q)) heap.push(*next);
    if (auto next = best_move(m.vertex)) heap.push(*next);
  }
  // Weights of moved vertices: projections onto their new cluster's basis.
  for (std::uint32_t p = 0; p < mesh.vertex_count(); ++p) {
    if (!moved[p]) continue;
    const int k = label[p];
    compressed.weights.row(p).setZero();
    const int n_k = compressed.components_of(k);
    if (n_k > 0)
      compressed.weights.row(p).head(n_k) =
          (x.row(p) - compressed.means.row(k)) * compressed.representatives[k].transpose();
  }
  return moves;
}

void supercluster(const Mesh& mesh, int max_clusters, SuperclusterMethod method,
                  CompressedTransfer& compressed) {
  const int k = static_cast<int>(compressed.clusters());
  const auto& label = compressed.cluster_of_vertex;
  std::vector<std::int32_t> group(k);
  std::iota(group.begin(), group.end(), 0);
  const int cap = std::max(1, max_clusters);

  if (method == SuperclusterMethod::greedy_merge) {
    std::vector<int> size(k, 1);
    while (true) {
      // Triangles shared by each pair of superclusters: merging the pair
      // removes exactly one draw of each.
      std::map<std::pair<int, int>, int> shared;
      for (const auto& t : mesh.triangles) {
        std::array<int, 3> g{group[label[t[0]]], group[label[t[1]]], group[label[t[2]]]};
        std::sort(g.begin(), g.end());
        const auto end = std::unique(g.begin(), g.end());
        for (auto a = g.begin(); a != end; ++a)
          for (auto b = a + 1; b != end; ++b) ++shared[{*a, *b}];
      }
      std::pair<int, int> best{-1, -1};
      int best_count = 0;
      for (const auto& [pair, count] : shared)
        if (count > best_count && size[pair.first] + size[pair.second] <= cap)
          best = pair, best_count = count;
      if (best_count == 0) break;
      for (auto& g : group)
        if (g == best.second) g = best.first;
      size[best.first] += size[best.second];
      size[best.second] = 0;
    }
  } else {
    // Chen: seed with the most populous unselected cluster, then add the
    // unselected cluster sharing the most triangles with the group so far.
    std::vector<Eigen::Index> population(k, 0);
    for (auto l : label) ++population[l];
    std::vector<std::uint8_t> selected(k, 0);
    int remaining = k, next_id = 0;
    while (remaining > 0) {
      int seed = -1;
      for (int j = 0; j < k; ++j)
        if (!selected[j] && (seed < 0 || population[j] > population[seed])) seed = j;
      std::vector<std::uint8_t> in_group(k, 0);
      in_group[seed] = selected[seed] = 1;
      group[seed] = next_id;
      --remaining;
      for (int members = 1; members < cap && remaining > 0; ++members) {
        std::vector<int> shared(k, 0);
        for (const auto& t : mesh.triangles) {
          const int a = label[t[0]], b = label[t[1]], c = label[t[2]];
          if (!in_group[a] && !in_group[b] && !in_group[c]) continue;
          std::array<int, 3> ids{a, b, c};
          std::sort(ids.begin(), ids.end());
          const auto end = std::unique(ids.begin(), ids.end());
          for (auto it = ids.begin(); it != end; ++it)
            if (!selected[*it]) ++shared[*it];
        }
        int best = -1;
        for (int j = 0; j < k; ++j)
          if (!selected[j] && shared[j] > 0 && (best < 0 || shared[j] > shared[best])) best = j;
        if (best < 0) break;  // nothing adjacent is left: start a new group
        in_group[best] = selected[best] = 1;
        group[best] = next_id;
        --remaining;
      }
      ++next_id;
    }
  }
  // Compact ids to 0..S-1 in order of first appearance.
  std::map<int, int> compact;
  compressed.supercluster_of_cluster.resize(k);
  for (int j = 0; j < k; ++j) {
    auto [it, inserted] = compact.emplace(group[j], static_cast<int>(compact.size()));
    compressed.supercluster_of_cluster[j] = it->second;
  }
}

}  // namespace prt::clustering
