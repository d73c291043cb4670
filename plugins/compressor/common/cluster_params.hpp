// Parameters shared by the clustering compressors (VQ, CPCA): LBG options and
// the cluster-coherence passes. Header-only so each plug-in stays one library.
#pragma once
#include <algorithm>
#include <array>

#include "prt/clustering.hpp"
#include "prt/compressor.hpp"
#include "prt/log.hpp"
#include "prt/plugin.hpp"

namespace prt::compressor_params {

// Each key once: its schema record and its reader.
inline constexpr auto kClusters =
    param::integer("clusters", "256", 1, 1 << 24, "number of clusters");
inline constexpr auto kInit = param::choice<clustering::Init>(
    "init", "kmeans++",
    {{"kmeans++", clustering::Init::kmeans_plus_plus}, {"hyperbox", clustering::Init::hyperbox}},
    "LBG start: k-means++ or the thesis's random points in the data's hyper-box");
inline constexpr auto kIterations =
    param::integer("iterations", "30", 1, 10000, "LBG iterations at most");
inline constexpr auto kTolerance =
    param::real("tolerance", "1e-4", 0, 1, "LBG stops when the energy falls by less than this");
inline constexpr auto kSeed = param::integer("seed", "1", 0, 9.2e18, "random seed");
inline constexpr auto kAlpha =
    param::real("alpha", "0", 0, 1e6,
                "geometry coherence (Chen): weight of the distance to the cluster, per "
                "bounding-box diagonal");
inline constexpr auto kReclassify =
    param::boolean("reclassify", "false", "move boundary vertices to lower overdraw");
inline constexpr auto kErrorBudget =
    param::real("error_budget", "0.05", 0, 10, "reclassification: allowed relative SE increase");
enum class Grouping { none, greedy, chen };
inline constexpr auto kSupercluster = param::choice<Grouping>(
    "supercluster", "none",
    {{"none", Grouping::none}, {"greedy", Grouping::greedy}, {"chen", Grouping::chen}},
    "group clusters into superclusters");
inline constexpr auto kRegisters = param::integer(
    "registers", "256", 1, 65536, "superclusters: constant registers; (n'+1) per cluster");

constexpr std::array<ParamSpecRecord, 10> clustering() {
  return param::records(kClusters, kInit, kIterations, kTolerance, kSeed, kAlpha, kReclassify,
                        kErrorBudget, kSupercluster, kRegisters);
}

// Read once, in the constructor, so a bad value is found before any ray.
inline clustering::LbgOptions lbg_options(const Params& p) {
  clustering::LbgOptions o;
  o.clusters = static_cast<int>(kClusters(p));
  o.init = kInit(p);
  o.max_iterations = static_cast<int>(kIterations(p));
  o.tolerance = kTolerance(p);
  o.seed = static_cast<std::uint64_t>(kSeed(p));
  o.alpha = kAlpha(p);
  return o;
}

// Refuses an encoding (read from a bake file) beyond a compressor's budget:
// more than `clusters` clusters or `components` components (< 0: any), or a
// sparse form.
inline void check_budget(const CompressedTransfer& c, const Param<std::int64_t>* clusters_key,
                         std::int64_t clusters, const Param<std::int64_t>* components_key,
                         std::int64_t components) {
  if (c.sparse()) throw Error("the encoding is sparse, which this compressor does not make");
  if (clusters_key && c.clusters() > clusters)
    throw Error("the encoding has " + std::to_string(c.clusters()) + " clusters, more than " +
                std::string(clusters_key->name()) + " = " + std::to_string(clusters));
  if (components_key && c.components > components)
    throw Error("the encoding has " + std::to_string(c.components) + " components, more than " +
                std::string(components_key->name()) + " = " + std::to_string(components));
}

// The options with the mesh of this encode (geometry-coherent clustering needs one).
inline clustering::LbgOptions with_mesh(clustering::LbgOptions o, const Params& p,
                                        const Mesh* mesh) {
  o.mesh = mesh;
  if (o.alpha > 0 && !mesh) p.fail(kAlpha.name(), "geometry-coherent clustering needs a mesh");
  return o;
}

// The options with where this encode keeps its state (the checkpoint its
// ranks share: LBG keeps each rank's labels and rank 0's means; CPCA's
// passes are kept by a single process only).
inline clustering::LbgOptions kept_in(clustering::LbgOptions o, const Distribution& where) {
  o.keep = where.checkpoint;
  o.keep_seconds = where.checkpoint_seconds;
  return o;
}

// The coherence passes a scene asks for, read once in the constructor.
struct CoherenceOptions {
  bool reclassify = false;
  double error_budget = 0.05;
  bool supercluster = false;
  clustering::SuperclusterMethod method = clustering::SuperclusterMethod::greedy_merge;
  int registers = 256;
};

inline CoherenceOptions coherence_options(const Params& p) {
  CoherenceOptions o;
  o.reclassify = kReclassify(p);
  o.error_budget = kErrorBudget(p);
  const Grouping grouping = kSupercluster(p);
  o.supercluster = grouping != Grouping::none;
  o.method = grouping == Grouping::chen ? clustering::SuperclusterMethod::chen_selection
                                        : clustering::SuperclusterMethod::greedy_merge;
  o.registers = static_cast<int>(kRegisters(p));
  return o;
}

// Reclassification, then superclustering, as the scene asks. Distributed,
// every part calls it after gather_rows: the first holds the whole
// compressed form and runs both passes, the others take back their rows
// that reclassification changed.
inline void improve_coherence(const CoherenceOptions& o, const Params& p,
                              const clustering::Rows& rows, const Mesh* mesh,
                              CompressedTransfer& compressed) {
  if (!mesh) {
    if (o.reclassify || o.supercluster)
      p.fail(o.reclassify ? kReclassify.name() : kSupercluster.name(),
             "cluster coherence needs the mesh");
    return;
  }
  const bool first = rows.parts->first();
  if (first && (o.reclassify || o.supercluster))
    compressed.statistics["overdraw_before_coherence"] =
        average_overdraw(*mesh, compressed.cluster_of_vertex);
  if (o.reclassify) {
    const std::size_t moves = clustering::reclassify(rows, *mesh, o.error_budget, compressed);
    if (first) compressed.statistics["reclassified_vertices"] = static_cast<double>(moves);
  }
  if (o.supercluster && first) {
    const int per_cluster = compressed.components + 1;  // RGB registers: c_0 .. c_n'
    const int cap = std::max<int>(1, o.registers / per_cluster);
    clustering::supercluster(*mesh, cap, o.method, compressed);
    compressed.statistics["superclusters"] =
        1.0 + *std::max_element(compressed.supercluster_of_cluster.begin(),
                                compressed.supercluster_of_cluster.end());
  }
}

// A budget larger than the data can use is used as far as it goes, with a
// warning naming the key and the value used: clusters beyond the vertices
// (LBG also drops clusters left empty), components beyond the coefficients
// or beyond what a cluster's members span.
inline void report_budget_used(const std::string& name, const Params& p,
                               const CompressedTransfer& c) {
  const auto warn = [&](const std::string& key, std::int64_t asked, std::int64_t used,
                        const char* why) {
    const std::string where = p.location(key).str();  // empty for parameters made in code
    log_warning((where.empty() ? "" : where + ": ") + "compressor \"" + name + "\": " + key +
                " = " + std::to_string(asked) + " is more than " + why + "; " +
                std::to_string(used) + " used");
  };
  if (kClusters.given(p) && c.clusters() < kClusters(p))
    warn(kClusters.name(), kClusters(p), c.clusters(),
         "this transfer supports (vertices, or clusters LBG left empty)");
  if (p.has("components") && c.components < p.get_int("components"))
    warn("components", p.get_int("components"), c.components,
         "this transfer supports (its coefficients per vertex, or a cluster's members)");
}

// The compressed form of clusters and their models, then the coherence
// passes. Distributed: the compressed rows are gathered on rank 0, which
// reclassifies (with every row gathered too) and superclusters.
inline CompressedTransfer finish(const std::string& name, const CoherenceOptions& o,
                                 const Params& p, const clustering::Rows& rows,
                                 const std::vector<std::int32_t>& labels,
                                 const std::vector<clustering::ClusterModel>& models,
                                 const Mesh* mesh) {
  CompressedTransfer c = clustering::assemble(rows, labels, models, name);
  if (rows.parts->first()) report_budget_used(name, p, c);
  if (!rows.distributed()) {
    improve_coherence(o, p, rows, mesh, c);
    rows.release_all();  // moved vertices were re-read where they lie
    return c;
  }
  clustering::gather_rows(rows, c);
  improve_coherence(o, p, rows, mesh, c);
  return c;
}

// Why a clustering compressor with these options cannot run distributed
// (empty: it can).
inline std::string why_not_distributed(const CoherenceOptions&, const clustering::LbgOptions& l) {
  if (l.alpha > 0)
    return "clusters by geometry (alpha > 0), which needs every vertex in one process";
  return "";
}

inline clustering::Rows rows_of(const TransferSignal& signal, const Distribution& where) {
  return clustering::Rows(signal, where.row_parts(signal.vertices()));
}

// Refuses NaN/Inf transfer with the vertex that holds it.
inline void require_finite(const TransferSignal& signal) {
  const auto rows = signal.rows();
  for (Eigen::Index p = 0; p < signal.vertices(); ++p) {
    if (!rows.row(p).allFinite())
      throw Error("transfer of vertex " + std::to_string(p) + " holds NaN or Inf");
    if (p % 4096 == 4095) signal.release(p - 4095, p + 1);
  }
  signal.release(0, signal.vertices());
}

template <std::size_t A, std::size_t B>
constexpr std::array<ParamSpecRecord, A + B> join(const std::array<ParamSpecRecord, A>& a,
                                                  const std::array<ParamSpecRecord, B>& b) {
  std::array<ParamSpecRecord, A + B> out{};
  for (std::size_t i = 0; i < A; ++i) out[i] = a[i];
  for (std::size_t i = 0; i < B; ++i) out[A + i] = b[i];
  return out;
}

}  // namespace prt::compressor_params
