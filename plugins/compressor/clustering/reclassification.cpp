// Reclassification (Sloan et al. 2003, "Clustered Principal Components for
// Precomputed Radiance Transfer", section 5, first technique): boundary
// vertices move to a neighbouring cluster where that lowers overdraw, in
// order of overdraw reduction per unit of error added, until the moves have
// spent the error budget (a fraction of the encoding's squared error). Each
// moved vertex's weights are its projection onto its new cluster's basis.
#include <algorithm>
#include <array>
#include <limits>
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

struct Move {
  double priority;  // overdraw reduction per unit error increase
  int reduction;
  double increase;
  std::uint32_t vertex;
  std::int32_t target;
  std::uint32_t version;
  bool operator<(const Move& o) const { return priority < o.priority; }
};

class Reclassifier {
 public:
  Reclassifier(RowsRef x, const Mesh& mesh, CompressedTransfer& compressed)
      : x_(x),
        mesh_(mesh),
        compressed_(compressed),
        label_(compressed.cluster_of_vertex),
        adjacency_(adjacency(mesh)),
        version_(mesh.vertex_count(), 0),
        moved_(mesh.vertex_count(), 0) {}

  // The move of vertex p to a neighbour's cluster with the most overdraw
  // reduction per unit of error added; none when no move reduces overdraw.
  std::optional<Move> best_move(std::uint32_t p) const {
    std::set<std::int32_t> candidates;
    for (auto q : adjacency_.neighbours[p])
      if (label_[q] != label_[p]) candidates.insert(label_[q]);
    if (candidates.empty()) return std::nullopt;
    const double own = error_in(x_, p, compressed_, label_[p]);
    std::optional<Move> best;
    for (std::int32_t target : candidates) {
      const int reduction = overdraw_reduction(p, target);
      if (reduction <= 0) continue;
      const double increase = error_in(x_, p, compressed_, target) - own;
      const double priority =
          increase <= 0 ? std::numeric_limits<double>::infinity() : reduction / increase;
      if (!best || priority > best->priority)
        best = Move{priority, reduction, increase, p, target, version_[p]};
    }
    return best;
  }

  // Spends the budget on the best moves; a move re-evaluates its vertex and
  // neighbours (their older entries in the heap go stale).
  std::size_t spend(std::priority_queue<Move>& heap, double budget) {
    double spent = 0;
    std::size_t moves = 0;
    while (!heap.empty()) {
      const Move m = heap.top();
      heap.pop();
      if (m.version != version_[m.vertex]) continue;  // stale: re-evaluated since
      if (spent + m.increase > budget) continue;      // too costly; cheaper moves may remain
      spent += m.increase;
      label_[m.vertex] = m.target;
      moved_[m.vertex] = 1;
      ++moves;
      for (std::uint32_t q : adjacency_.neighbours[m.vertex]) ++version_[q];
      ++version_[m.vertex];
      for (std::uint32_t q : adjacency_.neighbours[m.vertex])
        if (auto next = best_move(q)) heap.push(*next);
      if (auto next = best_move(m.vertex)) heap.push(*next);
    }
    return moves;
  }

  // Weights of moved vertices: projections onto their new cluster's basis.
  void project_moved() {
    for (std::uint32_t p = 0; p < mesh_.vertex_count(); ++p) {
      if (!moved_[p]) continue;
      const int k = label_[p];
      compressed_.weights.row(p).setZero();
      const int n_k = compressed_.components_of(k);
      if (n_k > 0)
        compressed_.weights.row(p).head(n_k) =
            (x_.row(p) - compressed_.means.row(k)) * compressed_.representatives[k].transpose();
    }
  }

 private:
  // Draws saved over p's triangles if p joined cluster `target`.
  int overdraw_reduction(std::uint32_t p, std::int32_t target) const {
    int reduction = 0;
    for (auto t : adjacency_.triangles_of[p]) {
      std::array<std::int32_t, 3> ids{};
      for (int i = 0; i < 3; ++i) ids[i] = label_[mesh_.triangles[t][i]];
      const int before = distinct(ids[0], ids[1], ids[2]);
      for (int i = 0; i < 3; ++i)
        if (mesh_.triangles[t][i] == p) ids[i] = target;
      reduction += before - distinct(ids[0], ids[1], ids[2]);
    }
    return reduction;
  }

  RowsRef x_;
  const Mesh& mesh_;
  CompressedTransfer& compressed_;
  std::vector<std::int32_t>& label_;
  const Adjacency adjacency_;
  std::vector<std::uint32_t> version_;
  std::vector<std::uint8_t> moved_;
};

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
  double total = 0;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    total += error_in(x, p, compressed, compressed.cluster_of_vertex[p]);
    swept(p);
  }
  Reclassifier reclassifier(x, mesh, compressed);
  std::priority_queue<Move> heap;
  for (std::uint32_t p = 0; p < mesh.vertex_count(); ++p) {
    if (auto m = reclassifier.best_move(p)) heap.push(*m);
    swept(p);
  }
  if (release) release(0, x.rows());
  const std::size_t moves = reclassifier.spend(heap, error_budget * total);
  reclassifier.project_moved();
  return moves;
}

}  // namespace prt::clustering
