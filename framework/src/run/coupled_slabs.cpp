#include "coupled_slabs.hpp"

#include <algorithm>
#include <cstring>
#include <optional>

#include "prt/checkpoint.hpp"
#include "prt/glossy.hpp"
#include "prt/progress.hpp"
#include "slab_parts.hpp"

namespace prt {

namespace {

// A slab's parts: "trace-rays" is written last and marks the slab kept.
constexpr const char* kRays = "trace-rays";
constexpr const char* kRows = "trace-transfer";
constexpr const char* kBits = "trace-bits";
constexpr const char* kHits = "trace-hits";

// Hits as int32 values: the slab's per-vertex counts, then four values per
// hit (direction, triangle, and the bits of u and v).
void keep_hits(const CheckpointStore& store, const SlabRange& slab, const HitLists& hits) {
  std::size_t total = 0;
  for (const auto& list : hits) total += list.size();
  std::vector<std::int32_t> saved;
  saved.reserve(hits.size() + 4 * total);
  for (const auto& list : hits) saved.push_back(static_cast<std::int32_t>(list.size()));
  for (const auto& list : hits)
    for (const SurfaceHit& h : list) {
      std::int32_t u = 0, v = 0;
      std::memcpy(&u, &h.u, sizeof u);
      std::memcpy(&v, &h.v, sizeof v);
      saved.insert(saved.end(), {std::int32_t(h.direction), std::int32_t(h.triangle), u, v});
    }
  store.save(rows_name(kHits, slab), saved);
}

// The kept hits of a slab into hits[slab.first, slab.last), each checked
// against the mesh and the directions.
void load_hits(const CheckpointStore& store, const SlabRange& slab, const Mesh& mesh,
               std::size_t directions, HitLists& hits) {
  const std::string name = rows_name(kHits, slab);
  const std::vector<std::int32_t> saved = store.load_ints(name);
  std::size_t total = 0;
  bool counts_valid = saved.size() >= slab.size();
  for (std::size_t i = 0; counts_valid && i < slab.size(); ++i) {
    counts_valid = saved[i] >= 0;
    total += std::size_t(std::max(saved[i], 0));
  }
  if (!counts_valid || saved.size() != slab.size() + 4 * total)
    throw misshapen_part(store, name, std::to_string(saved.size()) + " values",
                         "a count per vertex and four values per hit");
  const std::int32_t* at = saved.data() + slab.size();
  for (std::size_t i = 0; i < slab.size(); ++i) {
    auto& list = hits[slab.first + i];
    list.resize(std::size_t(saved[i]));
    for (SurfaceHit& h : list) {
      h.direction = std::uint32_t(at[0]);
      h.triangle = std::uint32_t(at[1]);
      std::memcpy(&h.u, &at[2], sizeof h.u);
      std::memcpy(&h.v, &at[3], sizeof h.v);
      if (h.direction >= directions || h.triangle >= mesh.triangles.size())
        throw misshapen_part(store, name,
                             "a hit of direction " + std::to_string(h.direction) + " on triangle " +
                                 std::to_string(h.triangle),
                             "directions below " + std::to_string(directions) +
                                 " and triangles below " + std::to_string(mesh.triangles.size()));
      at += 4;
    }
  }
}

}  // namespace

TransportResult trace_slab(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                           const RayCaster* caster, std::size_t first, std::size_t last,
                           bool keep_visibility, bool keep_hits, Progress* progress) {
  TransportOptions transport;
  transport.shadowed = plan.shadowed;
  transport.keep_visibility = keep_visibility;
  transport.keep_hits = keep_hits;
  transport.first_vertex = first;
  transport.last_vertex = last;
  transport.caster = caster;
  return keep_visibility
             ? diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), transport, progress)
             : diffuse_transfer(mesh, set, *plan.basis, transport, progress);
}

namespace {

// A slab just traced: kept in the store (its rays' count last, which marks
// it kept) and moved into `out`, whose rows are the whole mesh's.
void keep_traced_slab(const CheckpointStore& store, const SlabRange& slab, bool keep_visibility,
                      bool hits, std::size_t words, TransportResult& traced, TransportResult& out) {
  if (keep_visibility) {
    keep_bits(store, kBits, slab, traced.visibility);
    if (slab.size() > 0)
      std::memcpy(out.visibility.words(slab.first), traced.visibility.words(0),
                  slab.size() * words * sizeof(std::uint64_t));
  } else {
    store.save(rows_name(kRows, slab), traced.transfer.coefficients);
    out.transfer.coefficients.middleRows(Eigen::Index(slab.first), Eigen::Index(slab.size())) =
        traced.transfer.coefficients;
  }
  if (hits) {
    keep_hits(store, slab, traced.hits);
    std::move(traced.hits.begin(), traced.hits.end(), out.hits.begin() + long(slab.first));
  }
  keep_count(store, kRays, slab, traced.rays_cast);
  out.rays_cast += traced.rays_cast;
}

}  // namespace

TransportResult slabbed_trace(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                              const RunOptions& options) {
  const CheckpointStore& store = *options.checkpoint;
  const std::size_t v = mesh.vertex_count(), s = std::size_t(set.size());
  const std::size_t words = VisibilityBits::words_for(s);
  const auto slabs = transfer_slabs(0, v, options.slab_vertices);
  say_kept_slabs(
      store, slabs, [&](const SlabRange& slab) { return store.has(rows_name(kRays, slab)); },
      "the trace", [&](const std::string& text) { options.message(text); });
  Stopwatch clock;
  TransportResult out;
  const Eigen::Index cols = plan.keep_visibility ? 0 : plan.basis->size();
  out.transfer.coefficients.resize(Eigen::Index(v), cols);
  if (plan.keep_visibility) out.visibility = VisibilityBits(v, s);
  const bool hits = plan.bounces > 0;
  if (hits) out.hits.resize(v);
  std::optional<RayCaster> caster;
  Progress progress("bake transfer", double(v), plan.shadowed ? "rays" : "", options.quiet);
  // The slabs not kept yet, traced here (shared: this rank's share of them)...
  const SlabSharing sharing{options.comm};
  std::vector<bool> here(slabs.size(), false);
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    const SlabRange& slab = slabs[i];
    if (!sharing.mine(i) || store.has(rows_name(kRays, slab))) continue;
    if (plan.shadowed && !caster) caster.emplace(plan.surfaces(mesh));
    TransportResult traced = trace_slab(plan, mesh, set, caster ? &*caster : nullptr, slab.first,
                                        slab.last, plan.keep_visibility, hits, &progress);
    keep_traced_slab(store, slab, plan.keep_visibility, hits, words, traced, out);
    here[i] = true;
  }
  caster.reset();
  sharing.barrier();  // every slab is kept
  // ... and the others read back.
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    if (here[i]) continue;
    const SlabRange& slab = slabs[i];
    if (plan.keep_visibility)
      copy_kept_bits(store, slab, {0, v}, words, out.visibility, kBits);
    else
      out.transfer.coefficients.middleRows(Eigen::Index(slab.first), Eigen::Index(slab.size())) =
          kept_rows(store, slab, cols, kRows);
    if (hits) load_hits(store, slab, mesh, s, out.hits);
    const std::uint64_t rays = kept_count(store, kRays, slab);
    progress.add(double(slab.size()), double(rays));
    out.rays_cast += rays;
  }
  sharing.barrier();  // every rank has read them
  progress.finish();
  out.trace_seconds = clock.seconds();
  return out;
}

TransferSignal slabbed_glossy_transfer(const BakePlan& plan, const Mesh& mesh,
                                       const DirectionSet& set, const VisibilityBits& visibility,
                                       const std::vector<Frame>& frames, const RunOptions& options,
                                       Progress* progress) {
  const GlossyOperator& glossy = plan.glossy_operator;
  if (!options.checkpoint)
    return glossy_transfer(mesh, set, visibility, *plan.basis, glossy, frames, plan.glossy_method,
                           progress);
  const std::size_t s = std::size_t(set.size()), words = VisibilityBits::words_for(s);
  TransferSignal out;
  out.kind = "glossy";
  out.exit_rows = glossy.rows();
  out.coefficients = rows_in_slabs(
      *options.checkpoint, options.checkpoint_prefix + "glossy", mesh.vertex_count(),
      Eigen::Index(glossy.rows()) * plan.basis->size(), options.slab_vertices,
      [&](const SlabRange& slab) {
        VisibilityBits bits(slab.size(), s);
        if (slab.size() > 0)
          std::memcpy(bits.words(0), visibility.words(slab.first),
                      slab.size() * words * sizeof(std::uint64_t));
        return glossy_transfer(mesh, set, bits, *plan.basis, glossy, frames, plan.glossy_method,
                               progress, slab.first)
            .coefficients;
      },
      "the glossy matrices", [&](const std::string& text) { options.message(text); },
      [&](const SlabRange& slab) {
        if (progress) progress->add(double(slab.size()));
      },
      SlabSharing{options.comm});
  return out;
}

MatrixXfRow slabbed_subsurface(const Mesh& mesh, const MatrixXfRow& transfer,
                               const SubsurfaceMaterial& material, const RunOptions& options,
                               const std::string& what) {
  if (!options.checkpoint) return subsurface_transfer(mesh, transfer, material);
  std::optional<SubsurfaceScattering> scattering;  // built only when a slab is missing
  return rows_in_slabs(
      *options.checkpoint, options.checkpoint_prefix + what, mesh.vertex_count(), transfer.cols(),
      options.slab_vertices,
      [&](const SlabRange& slab) {
        if (!scattering) scattering.emplace(mesh, transfer, material);
        return scattering->rows(slab.first, slab.last);
      },
      "subsurface scattering", [&](const std::string& text) { options.message(text); }, {},
      SlabSharing{options.comm});
}

}  // namespace prt
