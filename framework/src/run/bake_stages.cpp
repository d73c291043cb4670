// Stages 1-2 of a bake through a checkpoint: a per-vertex transfer slab by
// slab, any other transfer whole with its fitted basis. Each finished part is
// kept, so a killed bake rerun with the same command computes only the rest.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <memory>
#include <optional>

#include "coupled_slabs.hpp"
#include "kept_state.hpp"
#include "prt/basis.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/error.hpp"
#include "prt/frame.hpp"
#include "prt/glossy.hpp"
#include "prt/pipeline.hpp"
#include "prt/probe_transfer.hpp"
#include "prt/progress.hpp"
#include "prt/row_file.hpp"
#include "prt/transport.hpp"
#include "slab_parts.hpp"

namespace prt {

namespace {

// The kind and layout of a plan's transfer (what its rows mean).
void set_shape(const BakePlan& plan, TransferSignal& signal) {
  signal.kind = plan.glossy ? "glossy" : plan.probes ? "incident" : "diffuse";
  signal.exit_rows = exit_rows(plan);
  if (plan.channels.groups.size() > 1) {
    signal.channel_groups = static_cast<int>(plan.channels.groups.size());
    signal.group_of_channel = plan.channels.group_of_channel;
  }
}

// Stage 2 (and the fit) from the traced rays, the tracing's time first.
TransferOutcome transfer_from_rays(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                                   TransportResult traced, const RunOptions& options,
                                   bool want_direct) {
  StageTimes times;
  times.add(plan.keep_visibility ? "trace" : "trace + project", traced.trace_seconds);
  TransferOutcome out =
      plan.channels.groups.size() <= 1
          ? transfer_stage(plan, mesh, set, std::move(traced), options, want_direct)
          : channel_transfers(plan, mesh, set, std::move(traced), options, want_direct);
  times.append(out.times);
  out.times = std::move(times);
  return out;
}

// A slab is kept once both its parts exist (the transfer is saved last).
bool slab_kept(const CheckpointStore& store, const SlabRange& slab) {
  return store.has(rows_name("transfer", slab.first, slab.last)) &&
         store.has(rows_name("rays", slab.first, slab.last));
}

void keep_slab(const CheckpointStore& store, const SlabRange& slab, const MatrixXfRow& rows,
               std::uint64_t rays) {
  keep_count(store, "rays", slab, rays);
  store.save(rows_name("transfer", slab), rows);  // last: marks it kept
}

std::uint64_t kept_rays(const CheckpointStore& store, const SlabRange& slab) {
  return kept_count(store, "rays", slab);
}

Eigen::Index transfer_dimension(const BakePlan& plan) {
  return Eigen::Index(exit_rows(plan)) * plan.basis->size();
}

// Rows [first, last) of a per-vertex transfer, slab by slab through the
// checkpoint: kept slabs are loaded, the others computed and kept.
TransferOutcome slabbed_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                                 const RunOptions& options, std::size_t first, std::size_t last,
                                 bool on_disk) {
  const CheckpointStore& store = *options.checkpoint;
  const auto slabs = transfer_slabs(first, last, options.slab_vertices);
  const std::size_t kept = say_kept_slabs(
      store, slabs, [&](const SlabRange& slab) { return slab_kept(store, slab); }, "vertices",
      [&](const std::string& text) { options.message(text); });
  Stopwatch clock;
  std::optional<RayCaster> caster;
  if (plan.shadowed && kept < slabs.size()) caster.emplace(plan.surfaces(mesh));
  const std::vector<Frame> frames =
      plan.glossy && kept < slabs.size() ? tangent_frames(mesh) : std::vector<Frame>();
  TransferOutcome result;
  result.basis = plan.basis;
  TransferSignal& out = result.transfer;
  set_shape(plan, out);
  const Eigen::Index rows_total = static_cast<Eigen::Index>(last - first),
                     cols = transfer_dimension(plan);
  std::shared_ptr<RowFile> file;
  if (on_disk)
    file = RowFile::create(store.folder(), rows_total, cols);
  else
    out.coefficients.resize(rows_total, cols);
  Progress progress("bake transfer", double(last - first), plan.shadowed ? "rays" : "",
                    options.quiet);
  for (const auto& slab : slabs) {
    MatrixXfRow rows;
    std::uint64_t rays = 0;
    if (slab_kept(store, slab)) {
      rows = kept_rows(store, slab, cols);
      rays = kept_rays(store, slab);
      progress.add(double(slab.last - slab.first), double(rays));
    } else {
      TransferOutcome computed = slab_transfer(plan, mesh, set, caster ? &*caster : nullptr, frames,
                                               slab.first, slab.last, &progress);
      rows = std::move(computed.transfer.coefficients);
      rays = computed.rays_cast;
      keep_slab(store, slab, rows, rays);
    }
    const Eigen::Index at = static_cast<Eigen::Index>(slab.first - first);
    if (file)
      file->write(at, rows);
    else
      out.coefficients.middleRows(at, rows.rows()) = rows;
    result.rays_cast += rays;
  }
  if (file) {
    file->map();
    out.file = std::move(file);
  }
  result.times.add(plan.glossy ? "trace + glossy matrices (slabs)" : "trace + project (slabs)",
                   clock.seconds());
  return result;
}

TransferOutcome whole_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               const RunOptions& options, bool want_direct) {
  const CheckpointStore& store = *options.checkpoint;
  const bool direct = want_direct && plan.bounces > 0;
  if (store.has("transfer")) {
    options.message("resuming: the transfer kept in " + store.folder().string());
    TransferOutcome out;
    set_shape(plan, out.transfer);
    out.transfer.coefficients = store.load_floats("transfer");
    if (direct) {
      out.direct = out.transfer;
      out.direct.coefficients = store.load_floats("direct");
    }
    out.basis = plan.fit ? kept_basis(store, plan.new_basis) : plan.basis;
    read_metrics(store.load_text("metrics"), out.metrics);
    out.rays_cast = static_cast<std::uint64_t>(store.load_doubles("rays")(0, 0));
    return out;
  }
  // Traced in slabs, each kept; the stages after it keep their own parts
  // (the fit's iterations and basis, each bounce, each channel's transfer).
  // Distributed, every rank computes its share of each stage's slabs and
  // reads the rest: each ends with the whole transfer, and rank 0 keeps it.
  TransferOutcome out = transfer_from_rays(plan, mesh, set, slabbed_trace(plan, mesh, set, options),
                                           options, want_direct);
  if (!SlabSharing{options.comm}.root()) return out;
  if (plan.fit) keep_basis_state(store, *out.basis);
  if (direct) store.save("direct", out.direct.coefficients);
  store.save_text("metrics", metrics_text(out.metrics));
  store.save("rays", Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, double(out.rays_cast))));
  store.save("transfer", out.transfer.coefficients);  // last: its presence marks the stage done
  return out;
}

}  // namespace

namespace {

// An id of this run, the same on every rank: claims of a killed run carry
// another, so they do not hold a slab back.
std::string run_id(const Communicator& comm) {
  std::vector<char> id;
  if (comm.rank() == 0) {
    const std::string text =
        std::to_string(::getpid()) + "-" +
        std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
    id.assign(text.begin(), text.end());
  }
  comm.broadcast(id, 0);
  return Digest().add(std::string(id.begin(), id.end())).hex();
}

}  // namespace

bool per_vertex_transfer(const BakePlan& plan) {
  return !plan.fit && per_vertex_transfer_after_fit(plan);
}

bool per_vertex_transfer_after_fit(const BakePlan& plan) {
  return plan.bounces == 0 && !plan.subsurface && plan.channels.groups.size() <= 1;
}

bool fitted_per_vertex_transfer(const BakePlan& plan) {
  return plan.fit && !plan.glossy && per_vertex_transfer_after_fit(plan);
}

bool transfer_by_rows(const BakePlan& plan) {
  return per_vertex_transfer(plan) || fitted_per_vertex_transfer(plan);
}

TransferOutcome slab_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                              const RayCaster* caster, const std::vector<Frame>& frames,
                              std::size_t first, std::size_t last, Progress* progress) {
  if (!per_vertex_transfer(plan))
    throw Error(
        "bake: this transfer couples vertices (fitted basis, bounces, subsurface or "
        "per-channel transfers) and cannot be computed in slabs");
  TransportResult traced =
      trace_slab(plan, mesh, set, caster, first, last, plan.keep_visibility, false, progress);
  TransferOutcome out;
  out.basis = plan.basis;
  out.rays_cast = traced.rays_cast;
  out.transfer =
      plan.glossy ? glossy_transfer(mesh, set, traced.visibility, *plan.basis, plan.glossy_operator,
                                    frames, plan.glossy_method, nullptr, first)
                  : std::move(traced.transfer);
  return out;
}

TransferOutcome checkpointed_transfer(const BakePlan& plan, const Mesh& mesh,
                                      const DirectionSet& set, const RunOptions& options,
                                      bool want_direct, bool on_disk) {
  if (on_disk && (!options.checkpoint || options.traced || !transfer_by_rows(plan)))
    throw Error("bake: only a per-vertex transfer with a checkpoint folder is kept on disk");
  if (!options.checkpoint || options.traced)  // stages 1-2 as they run without a checkpoint
    return transfer_from_rays(plan, mesh, set, trace_stage(plan, mesh, set, options), options,
                              want_direct);
  if (per_vertex_transfer(plan))
    return slabbed_transfer(plan, mesh, set, options, 0, mesh.vertex_count(), on_disk);
  if (fitted_per_vertex_transfer(plan))  // the bits in slabs, the fit, then the rows
    return fitted_shard_transfer(plan, mesh, set, options, whole(Eigen::Index(mesh.vertex_count())),
                                 solo(), on_disk);
  return whole_transfer(plan, mesh, set, options, want_direct);
}

TransferOutcome coupled_shard_transfer(const BakePlan& plan, const Mesh& mesh,
                                       const DirectionSet& set, const RunOptions& options,
                                       const Shard& shard) {
  if (!options.checkpoint) throw Error("a distributed bake needs a checkpoint folder");
  SlabSharing{options.comm}.barrier();  // every rank sees the same kept stages
  TransferOutcome out = whole_transfer(plan, mesh, set, options, plan.bounces > 0);
  // The whole transfer moves (not copied: each rank would hold it twice);
  // the shard's rows are copied out of it with the plan's shape.
  auto whole = std::make_shared<TransferSignal>(std::move(out.transfer));
  out.transfer = TransferSignal();
  set_shape(plan, out.transfer);
  out.transfer.coefficients = whole->coefficients.middleRows(shard.first, shard.rows());
  out.whole = std::move(whole);
  return out;
}

TransferOutcome shard_transfer(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               const RunOptions& options, const Shard& shard,
                               const Communicator& comm, bool on_disk) {
  if (!options.checkpoint) throw Error("a distributed bake needs a checkpoint folder");
  const CheckpointStore& store = *options.checkpoint;
  const std::size_t v = mesh.vertex_count();
  const auto slabs = transfer_slabs(0, v, options.slab_vertices);
  // Ranks take slabs as they come free (a slab's cost depends on its part
  // of the mesh), by creating its claim file. Claims carry this run's id, so
  // those of a killed run do not hold a slab back.
  const std::string run = run_id(comm);
  say_kept_slabs(
      store, slabs, [&](const SlabRange& slab) { return slab_kept(store, slab); }, "vertices",
      [&](const std::string& text) { options.message(text); });
  Stopwatch clock;
  std::optional<RayCaster> caster;
  std::vector<Frame> frames;
  Progress progress("bake transfer (slabs done or taken)", double(slabs.size()), "", options.quiet);
  std::size_t traced_here = 0;
  for (const auto& slab : slabs) {
    progress.add(1);
    if (slab_kept(store, slab)) continue;
    if (!store.claim("claim-" + run + "." + rows_name("transfer", slab.first, slab.last)))
      continue;  // another rank has it
    if (plan.shadowed && !caster) caster.emplace(plan.surfaces(mesh));
    if (plan.glossy && frames.empty()) frames = tangent_frames(mesh);
    const TransferOutcome computed = slab_transfer(plan, mesh, set, caster ? &*caster : nullptr,
                                                   frames, slab.first, slab.last, nullptr);
    keep_slab(store, slab, computed.transfer.coefficients, computed.rays_cast);
    ++traced_here;
  }
  caster.reset();
  comm.barrier();  // every slab is kept
  TransferOutcome result;
  result.basis = plan.basis;
  result.times.add("trace + project (" + std::to_string(traced_here) + " slabs on this rank)",
                   clock.seconds());
  // This rank's rows (in memory, or in a file of its own), and the rays of every slab.
  TransferSignal& out = result.transfer;
  set_shape(plan, out);
  const Eigen::Index cols = transfer_dimension(plan);
  std::shared_ptr<RowFile> file;
  if (on_disk)
    file = RowFile::create(store.folder(), shard.rows(), cols);
  else
    out.coefficients.resize(shard.rows(), cols);
  for (const auto& slab : slabs) {
    result.rays_cast += kept_rays(store, slab);
    const std::size_t first = std::max(slab.first, std::size_t(shard.first)),
                      last = std::min(slab.last, std::size_t(shard.last));
    if (first >= last) continue;
    const MatrixXfRow rows = kept_rows(store, slab, cols);
    const Eigen::Index at = Eigen::Index(first) - shard.first, count = Eigen::Index(last - first);
    if (file)
      file->write(at, rows.middleRows(Eigen::Index(first - slab.first), count));
    else
      out.coefficients.middleRows(at, count) =
          rows.middleRows(Eigen::Index(first - slab.first), count);
  }
  if (file) {
    file->map();
    out.file = std::move(file);
  }
  return result;
}

namespace {

// The rays traced for the whole mesh's visibility, kept once every slab is.
constexpr const char* kVisibilityRays = "visibility-rays";
std::uint64_t kept_visibility_rays(const CheckpointStore& store) {
  return static_cast<std::uint64_t>(store.load_doubles(kVisibilityRays)(0, 0));
}

bool bits_kept(const CheckpointStore& store, const SlabRange& slab) {
  return store.has(rows_name("bits", slab.first, slab.last)) &&
         store.has(rows_name("bitrays", slab.first, slab.last));
}

// Traces a slab's visibility bits and keeps them (the bits last: they mark
// the slab kept).
void trace_bits(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                const CheckpointStore& store, std::optional<RayCaster>& caster,
                const SlabRange& slab, Progress& progress) {
  if (plan.shadowed && !caster) caster.emplace(plan.surfaces(mesh));
  TransportResult traced = trace_slab(plan, mesh, set, caster ? &*caster : nullptr, slab.first,
                                      slab.last, true, false, &progress);
  keep_count(store, "bitrays", slab, traced.rays_cast);
  keep_bits(store, "bits", slab, traced.visibility);
}

// The visibility bits of vertices [range.first, range.last) (this rank's
// shard), through slabs of the whole mesh kept in the checkpoint. With
// trace_all, the ranks first trace every slab not kept, each taking slabs as
// they come free (claim files), so that no rank waits for a slow part of the
// mesh; then each reads its range from the slabs. rays: those cast for the
// whole mesh, now or before.
VisibilityBits kept_visibility(const BakePlan& plan, const Mesh& mesh, const DirectionSet& set,
                               const RunOptions& options, const SlabRange& range,
                               const Communicator& comm, const std::string& run, bool trace_all,
                               std::uint64_t& rays) {
  const CheckpointStore& store = *options.checkpoint;
  const auto s = static_cast<std::size_t>(set.size());
  const std::size_t words = VisibilityBits::words_for(s);
  const auto slabs =
      slabs_of(0, mesh.vertex_count(), std::max<std::size_t>(1, options.slab_vertices));
  std::optional<RayCaster> caster;
  if (trace_all) {
    say_kept_slabs(
        store, slabs, [&](const SlabRange& slab) { return bits_kept(store, slab); },
        "visibility bits", [&](const std::string& text) { options.message(text); });
    Progress progress(
        comm.size() > 1 ? "trace visibility (slabs done or taken)" : "trace visibility",
        double(mesh.vertex_count()), plan.shadowed ? "rays" : "", options.quiet);
    for (const auto& slab : slabs) {
      if (bits_kept(store, slab) ||
          (comm.size() > 1 &&
           !store.claim("claim-" + run + "." + rows_name("bits", slab.first, slab.last)))) {
        progress.add(double(slab.last - slab.first));
        continue;
      }
      trace_bits(plan, mesh, set, store, caster, slab, progress);
    }
    progress.finish();
    comm.barrier();  // every slab is kept
    rays = 0;
    for (const auto& slab : slabs) rays += kept_count(store, "bitrays", slab);
    if (comm.rank() == 0)
      store.save(kVisibilityRays, Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, double(rays))));
  } else {
    rays = kept_visibility_rays(store);
  }
  VisibilityBits bits(range.last - range.first, s);
  Progress ignored("", 0, "", true);
  for (const auto& slab : slabs) {
    if (slab.last <= range.first || slab.first >= range.last) continue;
    // A slab missing (a rerun with another --slab-vertices) is traced here.
    if (!bits_kept(store, slab)) trace_bits(plan, mesh, set, store, caster, slab, ignored);
    copy_kept_bits(store, slab, range, words, bits);
  }
  return bits;
}

}  // namespace

TransferOutcome fitted_shard_transfer(const BakePlan& plan, const Mesh& mesh,
                                      const DirectionSet& set, const RunOptions& options,
                                      const Shard& shard, const Communicator& comm, bool on_disk) {
  if (!options.checkpoint) throw Error("bake: a fit through slabs needs a checkpoint folder");
  if (!fitted_per_vertex_transfer(plan))
    throw Error("bake: a fit through slabs needs a diffuse transfer each vertex gets alone");
  const CheckpointStore& store = *options.checkpoint;
  TransferOutcome result;
  // Rank 0 says whether the basis was kept, for every rank: a rank that
  // looked itself could see the marker rank 0 writes in this very run.
  std::vector<char> basis_kept(1, 0);
  if (comm.rank() == 0) basis_kept[0] = store.has(kFittedBasisMarker) ? 1 : 0;
  comm.broadcast(basis_kept, 0);
  const SlabRange own{std::size_t(shard.first), std::size_t(shard.last)};
  const bool rows_kept = basis_kept[0] && (own.first == own.last || slab_kept(store, own));
  if (basis_kept[0]) {
    result.basis = kept_basis(store, plan.new_basis);
    options.message("resuming: the fitted basis kept in " + store.folder().string());
  }
  const std::string run = comm.size() > 1 ? run_id(comm) : std::string("solo");
  MatrixXfRow rows;
  std::uint64_t rays = 0;  // the whole mesh's
  if (rows_kept) {
    const Eigen::Index cols = transfer_dimension(plan.with_basis(result.basis));
    rows = own.first < own.last ? kept_rows(store, own, cols) : MatrixXfRow(0, cols);
    rays = kept_visibility_rays(store);
  } else {
    // The ranks trace the visibility (unless the basis was kept, when every
    // slab was kept before it), then fit the basis together, each from its
    // own shard's bits.
    Stopwatch clock;
    const VisibilityBits bits =
        kept_visibility(plan, mesh, set, options, own, comm, run, !basis_kept[0], rays);
    result.times.add("trace visibility (slabs)", clock.seconds());
    if (!basis_kept[0]) {
      clock = Stopwatch();
      FitData fit{&mesh, &set, &bits, parts_over(comm, shard)};
      fit.checkpoint = &store;
      // Every rank fits; rank 0 keeps the result.
      result.basis = fit_fresh_basis(plan.new_basis, plan.basis_record.name, fit,
                                     comm.rank() == 0 ? &store : nullptr);
      result.times.add("fit basis (" + plan.basis_record.name + ")", clock.seconds());
    }
    clock = Stopwatch();
    rows = project_visibility(mesh, set, bits, *result.basis, own.first).coefficients;
    if (own.first < own.last) keep_slab(store, own, rows, rays);
    result.times.add("project", clock.seconds());
  }
  result.rays_cast = rays;
  comm.barrier();  // every rank's rows are kept (rank 0 writes the file from them)
  TransferSignal& out = result.transfer;
  set_shape(plan, out);
  if (on_disk) {
    auto file = RowFile::create(store.folder(), shard.rows(), rows.cols());
    file->write(0, rows);
    file->map();
    out.file = std::move(file);
  } else {
    out.coefficients = std::move(rows);
  }
  return result;
}

namespace {

// Rows [first, last) of the whole transfer: rank 0's from `own`, the others'
// from the kept parts `ranges` (in vertex order), a part at a time.
BakeData::StreamedRows kept_parts(const BakePlan& plan, const CheckpointStore& store,
                                  std::size_t vertices, std::vector<SlabRange> ranges,
                                  std::shared_ptr<const TransferSignal> own) {
  BakeData::StreamedRows rows;
  rows.rows = Eigen::Index(vertices);
  rows.cols = transfer_dimension(plan);
  // The slab last read stays loaded: write_bake asks for rows in order.
  auto cache = std::make_shared<std::pair<SlabRange, MatrixXfRow>>(SlabRange{0, 0}, MatrixXfRow());
  rows.read = [&store, own, ranges, cache, cols = rows.cols](Eigen::Index first, Eigen::Index count,
                                                             MatrixXfRow& out) {
    out.resize(count, cols);
    for (Eigen::Index done = 0; done < count;) {
      const std::size_t p = std::size_t(first + done);
      if (p < std::size_t(own->vertices())) {  // rank 0's rows, in memory or its file
        const Eigen::Index n = std::min(count - done, own->vertices() - Eigen::Index(p));
        out.middleRows(done, n) = own->rows().middleRows(Eigen::Index(p), n);
        own->release(Eigen::Index(p), Eigen::Index(p) + n);
        done += n;
        continue;
      }
      if (!(p >= cache->first.first && p < cache->first.last)) {
        const auto it = std::find_if(ranges.begin(), ranges.end(), [&](const SlabRange& r) {
          return p >= r.first && p < r.last;
        });
        if (it == ranges.end())
          throw Error("the checkpoint holds no slab with vertex " + std::to_string(p));
        *cache = {*it, kept_rows(store, *it, cols)};
      }
      const Eigen::Index at = Eigen::Index(p - cache->first.first);
      const Eigen::Index n = std::min(count - done, cache->second.rows() - at);
      out.middleRows(done, n) = cache->second.middleRows(at, n);
      done += n;
    }
  };
  return rows;
}

}  // namespace

BakeData::StreamedRows kept_transfer(const BakePlan& plan, const CheckpointStore& store,
                                     std::size_t vertices, std::size_t slab,
                                     std::shared_ptr<const TransferSignal> own) {
  return kept_parts(plan, store, vertices, transfer_slabs(0, vertices, slab), std::move(own));
}

BakeData::StreamedRows kept_shard_transfer(const BakePlan& plan, const CheckpointStore& store,
                                           std::size_t vertices, int ranks,
                                           std::shared_ptr<const TransferSignal> own) {
  std::vector<SlabRange> ranges;
  for (int r = 0; r < ranks; ++r) {
    const Shard shard = shard_of(Eigen::Index(vertices), r, ranks);
    ranges.push_back({std::size_t(shard.first), std::size_t(shard.last)});
  }
  return kept_parts(plan, store, vertices, std::move(ranges), std::move(own));
}

std::string bake_key(const SceneSpec& scene, const BakePlan& plan) {
  Digest digest;
  digest.add("prt bake format " + std::to_string(kBakeFormatVersion));
  // How rows are summed: a checkpoint kept by another projection would mix
  // its rows' rounding with this one's.
  digest.add("projection along trees in blocks of " + std::to_string(kProjectionBlock));
  digest.add(scene.text);
  for (const PluginRecord* record :
       {&plan.basis_record, &plan.exit_record, &plan.compressor_record})
    digest.add(one_line(*record));
  const std::string mesh_file = keys::mesh::file(scene.mesh);
  if (!mesh_file.empty()) digest.add_file(mesh_file);  // else generated: the text says all
  for (const Params& part : scene.mesh_parts)
    if (const std::string file = keys::place::file(part); !file.empty()) digest.add_file(file);
  return digest.hex();
}

namespace {

// A slab of probes: its validity flags are kept before its rows (which mark
// it kept), so a kept slab always has them.
void keep_probe_slab(const CheckpointStore& store, const SlabRange& slab,
                     const ProbeTransfer& traced) {
  store.save(rows_name("valid", slab),
             std::vector<std::int32_t>(traced.valid.begin(), traced.valid.end()));
  keep_slab(store, slab, traced.transfer.coefficients, traced.rays_cast);
}

void copy_kept_validity(const CheckpointStore& store, const SlabRange& slab,
                        std::vector<std::uint8_t>& valid) {
  const std::string name = rows_name("valid", slab);
  const std::vector<std::int32_t> flags = store.load_ints(name);
  if (flags.size() != slab.size())
    throw misshapen_part(store, name, std::to_string(flags.size()) + " flags",
                         std::to_string(slab.size()));
  for (std::size_t i = 0; i < flags.size(); ++i) {
    if (flags[i] != 0 && flags[i] != 1)
      throw misshapen_part(store, name, "a flag other than 0 or 1", "0 or 1");
    valid[slab.first + i] = std::uint8_t(flags[i]);
  }
}

// Once every slab is kept: every probe's validity (the renderers need all)
// and the shard's rows, with the rays of every slab.
void read_probe_slabs(const CheckpointStore& store, const std::vector<SlabRange>& slabs,
                      const Shard& shard, Eigen::Index cols, ProbeStage& out) {
  out.valid.assign(slabs.empty() ? 0 : slabs.back().last, 0);
  MatrixXfRow& rows = out.outcome.transfer.coefficients;
  rows.resize(shard.rows(), cols);
  for (const auto& slab : slabs) {
    out.outcome.rays_cast += kept_rays(store, slab);
    copy_kept_validity(store, slab, out.valid);
    const std::size_t first = std::max(slab.first, std::size_t(shard.first)),
                      last = std::min(slab.last, std::size_t(shard.last));
    if (first >= last) continue;
    const auto count = Eigen::Index(last - first);
    rows.middleRows(Eigen::Index(first) - shard.first, count) =
        kept_rows(store, slab, cols).middleRows(Eigen::Index(first - slab.first), count);
  }
}

}  // namespace

ProbeStage probe_shard_transfer(const BakePlan& plan, const Mesh& scene, const ProbeGrid& grid,
                                const DirectionSet& set, double invalid_fraction,
                                const RunOptions& options, const Shard& shard) {
  const Communicator& comm = options.comm ? *options.comm : solo();
  const std::size_t probes = grid.count();
  const Eigen::Index cols = transfer_dimension(plan);
  ProbeStage out;
  TransferOutcome& result = out.outcome;
  result.basis = plan.basis;
  set_shape(plan, result.transfer);
  Stopwatch clock;
  std::optional<RayCaster> caster;
  auto trace = [&](std::size_t first, std::size_t last, Progress* progress) {
    if (!caster) caster.emplace(scene);
    return probe_transfer(*caster, scene, grid, set, *plan.basis, *plan.exit, invalid_fraction,
                          plan.shadowed, progress, first, last);
  };
  if (!options.checkpoint) {  // one process holding every probe
    Progress progress("bake probes", double(probes), plan.shadowed ? "rays" : "", options.quiet);
    ProbeTransfer traced = trace(0, probes, &progress);
    progress.finish();
    result.transfer.coefficients = std::move(traced.transfer.coefficients);
    result.rays_cast = traced.rays_cast;
    out.valid = std::move(traced.valid);
    result.times.add("trace probes", clock.seconds());
    return out;
  }
  // Slab by slab through the checkpoint; the ranks of a distributed bake
  // take slabs as they come free (claims carry this run's id).
  const CheckpointStore& store = *options.checkpoint;
  const auto slabs = transfer_slabs(0, probes, options.slab_vertices);
  const std::string run = comm.size() > 1 ? run_id(comm) : std::string("solo");
  say_kept_slabs(
      store, slabs, [&](const SlabRange& slab) { return slab_kept(store, slab); }, "probes",
      [&](const std::string& text) { options.message(text); });
  {
    Progress progress(comm.size() > 1 ? "bake probes (slabs done or taken)" : "bake probes",
                      double(probes), plan.shadowed ? "rays" : "", options.quiet);
    for (const auto& slab : slabs) {
      if (slab_kept(store, slab) ||
          (comm.size() > 1 &&
           !store.claim("claim-" + run + "." + rows_name("probes", slab.first, slab.last)))) {
        progress.add(double(slab.size()));
        continue;
      }
      keep_probe_slab(store, slab, trace(slab.first, slab.last, &progress));
    }
    progress.finish();
  }
  caster.reset();
  comm.barrier();  // every slab is kept
  read_probe_slabs(store, slabs, shard, cols, out);
  result.times.add("trace probes (slabs)", clock.seconds());
  return out;
}

}  // namespace prt
