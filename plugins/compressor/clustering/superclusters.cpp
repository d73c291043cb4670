// Superclusters (Sloan et al. 2003, section 5, second technique; Chen 2005,
// chapter 4): groups of at most max_clusters clusters drawn as one, so a
// triangle whose corners lie in clusters of one group is drawn once. The
// greedy merge joins the neighbouring pair sharing the most triangles until
// no pair fits; Chen's selection seeds a group with the most populous
// cluster left and adds the cluster sharing the most triangles with it.
// Neither changes the approximation.
#include <algorithm>
#include <array>
#include <map>
#include <numeric>

#include "prt/clustering.hpp"

namespace prt::clustering {

namespace {

// Greedy merging of the pair of superclusters that shares the most triangles
// (merging it removes exactly one draw of each), within the cap.
void greedy_merge(const Mesh& mesh, const std::vector<std::int32_t>& label, int cap,
                  std::vector<std::int32_t>& group) {
  std::vector<int> size(group.size(), 1);
  while (true) {
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
}

// The unselected cluster sharing the most triangles with the group; -1 when
// none is adjacent.
int most_shared(const Mesh& mesh, const std::vector<std::int32_t>& label,
                const std::vector<std::uint8_t>& in_group,
                const std::vector<std::uint8_t>& selected) {
  const int k = int(selected.size());
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
  return best;
}

// Chen: seed with the most populous unselected cluster, then add the
// unselected cluster sharing the most triangles with the group so far.
void chen_selection(const Mesh& mesh, const std::vector<std::int32_t>& label, int cap,
                    std::vector<std::int32_t>& group) {
  const int k = int(group.size());
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
      const int best = most_shared(mesh, label, in_group, selected);
      if (best < 0) break;  // nothing adjacent is left: start a new group
      in_group[best] = selected[best] = 1;
      group[best] = next_id;
      --remaining;
    }
    ++next_id;
  }
}

}  // namespace

void supercluster(const Mesh& mesh, int max_clusters, SuperclusterMethod method,
                  CompressedTransfer& compressed) {
  const int k = static_cast<int>(compressed.clusters());
  const auto& label = compressed.cluster_of_vertex;
  std::vector<std::int32_t> group(k);
  std::iota(group.begin(), group.end(), 0);
  const int cap = std::max(1, max_clusters);
  if (method == SuperclusterMethod::greedy_merge)
    greedy_merge(mesh, label, cap, group);
  else
    chen_selection(mesh, label, cap, group);
  // Compact ids to 0..S-1 in order of first appearance.
  std::map<int, int> compact;
  compressed.supercluster_of_cluster.resize(k);
  for (int j = 0; j < k; ++j) {
    auto [it, inserted] = compact.emplace(group[j], static_cast<int>(compact.size()));
    compressed.supercluster_of_cluster[j] = it->second;
  }
}

}  // namespace prt::clustering
