#include "prt/transport.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <optional>
#include <random>
#include <utility>

#include "denormals.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/environment_sampler.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/row_blocks.hpp"
#include "prt/visible_products.hpp"

namespace prt {

std::size_t VisibilityBits::count_visible(std::size_t vertex) const {
  std::size_t count = 0;
  for (std::size_t w = 0; w < words_per_vertex_; ++w)
    count += std::popcount(bits_[vertex * words_per_vertex_ + w]);
  return count;
}

struct RayCaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayCaster::RayCaster(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw Error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);  // watertight: no leaks at shared edges
  // A high-quality BVH: its longer build (~0.03 s on the bunny) pays back in
  // traversal over the bake's millions of rays.
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_HIGH);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.positions.size()));
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    for (int c = 0; c < 3; ++c) vertices[3 * v + c] = mesh.positions[v][c];
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) indices[3 * t + c] = mesh.triangles[t][c];
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(impl_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(impl_->scene);
  // Offset relative to the object's size keeps rays off their own surface.
  const float extent = (mesh.bounds_max() - mesh.bounds_min()).norm();
  offset_ = std::max(1e-6f, 1e-4f * extent);
}

RayCaster::~RayCaster() = default;

bool front_face(const Mesh& mesh, std::uint32_t t, float u, float v,
                const Eigen::Vector3f& direction) {
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3f n =
      (1.f - u - v) * mesh.normals[tri[0]] + u * mesh.normals[tri[1]] + v * mesh.normals[tri[2]];
  return n.dot(direction) < 0.f;
}

namespace {

void fill_ray(RTCRay& r, const float* o, const float* d) {
  r.org_x = o[0], r.org_y = o[1], r.org_z = o[2];
  r.dir_x = d[0], r.dir_y = d[1], r.dir_z = d[2];
  r.tnear = 0.f, r.tfar = INFINITY, r.time = 0.f;
  r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
}

void fill_ray_hit(RTCRayHit& rh, const float* o, const float* d) {
  fill_ray(rh.ray, o, d);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

Eigen::Vector3f direction_of_ray(const RTCRay& r) {
  return {r.dir_x, r.dir_y, r.dir_z};
}

}  // namespace

void RayCaster::occluded(const float* origins, const float* directions, std::size_t count,
                         std::uint8_t* escaped, const float* far) const {
  const FlushDenormals flush_denormals;
  constexpr std::size_t kChunk = 256;
  RTCRay rays[kChunk];
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  for (std::size_t begin = 0; begin < count; begin += kChunk) {
    const std::size_t n = std::min(kChunk, count - begin);
    for (std::size_t i = 0; i < n; ++i)
      fill_ray(rays[i], origins + 3 * (begin + i), directions + 3 * (begin + i));
    if (far)
      for (std::size_t i = 0; i < n; ++i) rays[i].tfar = far[begin + i];
    rtcOccluded1M(impl_->scene, &context, rays, static_cast<unsigned>(n), sizeof(RTCRay));
    for (std::size_t i = 0; i < n; ++i) escaped[begin + i] = rays[i].tfar >= 0.f;
  }
}

void RayCaster::intersect(const Mesh& mesh, const float* origins, const float* directions,
                          std::size_t count, std::int64_t* triangle, float* u, float* v,
                          std::uint8_t* escaped) const {
  const FlushDenormals flush_denormals;
  constexpr std::size_t kChunk = 256;
  RTCRayHit rays[kChunk];
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  for (std::size_t begin = 0; begin < count; begin += kChunk) {
    const std::size_t n = std::min(kChunk, count - begin);
    for (std::size_t i = 0; i < n; ++i)
      fill_ray_hit(rays[i], origins + 3 * (begin + i), directions + 3 * (begin + i));
    rtcIntersect1M(impl_->scene, &context, rays, static_cast<unsigned>(n), sizeof(RTCRayHit));
    for (std::size_t i = 0; i < n; ++i) {
      const RTCHit& h = rays[i].hit;
      const bool hit = h.geomID != RTC_INVALID_GEOMETRY_ID &&
                       front_face(mesh, h.primID, h.u, h.v, direction_of_ray(rays[i].ray));
      triangle[begin + i] = hit ? std::int64_t(h.primID) : -1;
      u[begin + i] = h.u, v[begin + i] = h.v;
      if (escaped) escaped[begin + i] = h.geomID == RTC_INVALID_GEOMETRY_ID;
    }
  }
}

std::uint64_t RayCaster::trace_visibility(const Mesh& mesh, const std::uint32_t* vertices,
                                          std::size_t count, const float* directions, std::size_t s,
                                          std::uint64_t* bits, std::vector<SurfaceHit>* hits,
                                          std::size_t direction_stride) const {
  const FlushDenormals flush_denormals;
  constexpr unsigned kChunk = 1024;
  const std::size_t words = VisibilityBits::words_for(s);
  std::fill(bits, bits + count * words, 0);
  // Shadow rays need only occlusion; inter-reflection needs the hit points.
  std::vector<RTCRay> rays(hits ? 0 : kChunk);
  std::vector<RTCRayHit> ray_hits(hits ? kChunk : 0);
  std::uint32_t slot_of[kChunk], direction_of[kChunk];
  unsigned filled = 0;
  std::uint64_t cast = 0;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  auto mark_visible = [&](unsigned i) {
    bits[slot_of[i] * words + direction_of[i] / 64] |= std::uint64_t(1) << (direction_of[i] % 64);
  };
  auto flush = [&] {
    cast += filled;
    if (!hits) {
      rtcOccluded1M(impl_->scene, &context, rays.data(), filled, sizeof(RTCRay));
      for (unsigned i = 0; i < filled; ++i)
        if (rays[i].tfar >= 0.f) mark_visible(i);
    } else {
      rtcIntersect1M(impl_->scene, &context, ray_hits.data(), filled, sizeof(RTCRayHit));
      for (unsigned i = 0; i < filled; ++i) {
        const RTCHit& h = ray_hits[i].hit;
        if (h.geomID == RTC_INVALID_GEOMETRY_ID)
          mark_visible(i);
        else if (front_face(mesh, h.primID, h.u, h.v, direction_of_ray(ray_hits[i].ray)))
          hits[slot_of[i]].push_back({direction_of[i], h.primID, h.u, h.v});
      }
    }
    filled = 0;
  };
  for (std::size_t slot = 0; slot < count; ++slot) {
    const Eigen::Vector3f n = mesh.normals[vertices[slot]];
    const Eigen::Vector3f o = mesh.positions[vertices[slot]] + offset_ * n;
    const float* own = directions + slot * direction_stride;
    for (std::size_t k = 0; k < s; ++k) {
      const float* d = own + 3 * k;
      if (n.x() * d[0] + n.y() * d[1] + n.z() * d[2] <= 0.f) continue;
      if (hits)
        fill_ray_hit(ray_hits[filled], o.data(), d);
      else
        fill_ray(rays[filled], o.data(), d);
      slot_of[filled] = static_cast<std::uint32_t>(slot);
      direction_of[filled] = static_cast<std::uint32_t>(k);
      if (++filled == kChunk) flush();
    }
  }
  if (filled) flush();
  return cast;
}

std::vector<std::uint32_t> morton_order(const Mesh& mesh, std::size_t first, std::size_t last) {
  last = std::min(last, mesh.vertex_count());
  first = std::min(first, last);
  const Eigen::Vector3f lo = mesh.bounds_min();
  const Eigen::Vector3f extent = (mesh.bounds_max() - lo).cwiseMax(1e-30f);
  auto spread = [](std::uint64_t x) {  // 21 bits -> every third bit
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(last - first);
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    const std::size_t v = first + i;
    const Eigen::Vector3f q = ((mesh.positions[v] - lo).cwiseQuotient(extent) * 2097151.f);
    keyed[i] = {spread(std::uint64_t(q.x())) | spread(std::uint64_t(q.y())) << 1 |
                    spread(std::uint64_t(q.z())) << 2,
                static_cast<std::uint32_t>(v)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(keyed.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = keyed[i].second;
  return order;
}

namespace {

constexpr std::size_t kBlock = 32;  // vertices per task (tracing, then projecting their rays)

// A plug-in's matrix with an inf or NaN would spread it along the
// projection's trees to vertices that never see its direction.
void require_finite(const Eigen::MatrixXd& matrix, const char* what) {
  for (Eigen::Index c = 0; c < matrix.cols(); ++c)
    for (Eigen::Index r = 0; r < matrix.rows(); ++r)
      if (!std::isfinite(matrix(r, c)))
        throw Error(std::string(what) + " has a non-finite value (" + std::to_string(matrix(r, c)) +
                    ") at direction " + std::to_string(r) + ", coefficient " + std::to_string(c));
}

std::vector<float> to_float(const DirectionSet& set) {
  std::vector<float> out(3 * set.size());
  for (Eigen::Index k = 0; k < set.size(); ++k)
    for (int c = 0; c < 3; ++c) out[3 * k + c] = static_cast<float>(set.directions(k, c));
  return out;
}

// Unshadowed: every direction above the tangent plane counts as escaped.
void upper_hemisphere_bits(const Mesh& mesh, const std::uint32_t* vertices, std::size_t count,
                           const float* directions, std::size_t s, std::uint64_t* bits) {
  const std::size_t words = VisibilityBits::words_for(s);
  std::fill(bits, bits + count * words, 0);
  for (std::size_t slot = 0; slot < count; ++slot) {
    const Eigen::Vector3f n = mesh.normals[vertices[slot]];
    for (std::size_t k = 0; k < s; ++k) {
      const float* d = directions + 3 * k;
      if (n.x() * d[0] + n.y() * d[1] + n.z() * d[2] > 0.f)
        bits[slot * words + k / 64] |= std::uint64_t(1) << (k % 64);
    }
  }
}

// Projects one block: `bits` of `count` vertices -> count x n coefficients.
using BlockProjection = std::function<Eigen::MatrixXf(
    const std::uint32_t* vertices, std::size_t count, const std::vector<std::uint64_t>& bits)>;

// Traces the options' vertices in tasks of kBlock along their Morton curve;
// each task projects its block's bits with `project` into the result's rows
// (v x n). Without `project` the rows are left for the caller, and the bits
// are kept whatever the options say.
TransportResult trace_and_project(const Mesh& mesh, const DirectionSet& set, Eigen::Index n,
                                  const BlockProjection* project, const TransportOptions& options,
                                  Progress* progress) {
  const std::size_t last = std::min(options.last_vertex, mesh.vertex_count());
  const std::size_t first = std::min(options.first_vertex, last);
  const std::size_t v_count = last - first;
  const auto s = static_cast<std::size_t>(set.size());
  const std::size_t words = VisibilityBits::words_for(s);
  TransportResult result;
  result.transfer.coefficients.resize(static_cast<Eigen::Index>(v_count), n);
  const bool keep_bits = options.keep_visibility || !project;
  if (keep_bits) result.visibility = VisibilityBits(v_count, s);
  if (options.keep_hits) result.hits.resize(v_count);
  Stopwatch clock;
  std::optional<RayCaster> own_caster;
  const RayCaster* caster = options.caster;
  if (options.shadowed && !caster) caster = &own_caster.emplace(mesh);
  if (!options.shadowed) caster = nullptr;
  const std::vector<float> dirs_f = to_float(set);
  const std::vector<std::uint32_t> order = morton_order(mesh, first, last);
  std::atomic<std::uint64_t> rays{0};

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v_count, kBlock), [&](const auto& range) {
    const std::uint32_t* vertices = &order[range.begin()];
    const std::size_t count = range.size();
    std::vector<std::uint64_t> bits(count * words);
    std::vector<std::vector<SurfaceHit>> hits(options.keep_hits ? count : 0);
    if (caster) {
      const std::uint64_t cast =
          caster->trace_visibility(mesh, vertices, count, dirs_f.data(), s, bits.data(),
                                   hits.empty() ? nullptr : hits.data());
      rays += cast;
      if (progress) progress->add(double(count), double(cast));
    } else {
      upper_hemisphere_bits(mesh, vertices, count, dirs_f.data(), s, bits.data());
      if (progress) progress->add(double(count));
    }
    const Eigen::MatrixXf block = project ? (*project)(vertices, count, bits) : Eigen::MatrixXf();
    for (std::size_t slot = 0; slot < count; ++slot) {
      const std::size_t row = vertices[slot] - first;
      if (project)
        result.transfer.coefficients.row(static_cast<Eigen::Index>(row)) = block.row(slot);
      if (keep_bits) std::copy_n(&bits[slot * words], words, result.visibility.words(row));
      if (!hits.empty()) result.hits[row] = std::move(hits[slot]);
    }
  });
  result.trace_seconds = clock.seconds();
  result.rays_cast = rays;
  return result;
}

double cosine_over_pi(const Mesh& mesh, std::uint32_t vertex, const DirectionSet& set,
                      std::size_t k) {
  return mesh.normals[vertex].cast<double>().dot(set.directions.row(k)) / M_PI;
}

// Dense rows of cosine-weighted visibility / pi for `count` vertices whose
// visibility words lie consecutively at `bits`; vertex_of(slot) names each.
template <class VertexOf>
Eigen::MatrixXd rows_from_bits(const Mesh& mesh, const DirectionSet& set, std::size_t count,
                               VertexOf vertex_of, const std::uint64_t* bits) {
  const std::size_t words = VisibilityBits::words_for(set.size());
  Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(count, set.size());
  for (std::size_t slot = 0; slot < count; ++slot)
    for (std::size_t w = 0; w < words; ++w)
      for (std::uint64_t b = bits[slot * words + w]; b; b &= b - 1) {
        const std::size_t k = 64 * w + std::countr_zero(b);
        rows(slot, k) = cosine_over_pi(mesh, vertex_of(slot), set, k);
      }
  return rows;
}

}  // namespace

TransportResult diffuse_transfer(const Mesh& mesh, const DirectionSet& set,
                                 const Eigen::MatrixXd& projection, const TransportOptions& options,
                                 Progress* progress) {
  if (projection.rows() != set.size())
    throw Error("projection matrix has " + std::to_string(projection.rows()) + " rows for " +
                std::to_string(set.size()) + " directions");
  require_finite(projection, "the projection matrix");
  // The rays first, then per vertex the sum over its visible directions of
  // (n . d_k / pi) P_k, shared along trees of neighbours in fixed blocks of
  // the mesh (visible_times_in_blocks): only the directions where a vertex's
  // bits differ from its neighbour's cost flops. Unless the bits are kept,
  // a window of the mesh's grid at a time holds them (whole blocks: the
  // same rows).
  Stopwatch clock;
  const std::size_t last = std::min(options.last_vertex, mesh.vertex_count());
  const std::size_t first = std::min(options.first_vertex, last);
  const std::size_t window = options.keep_visibility ? last + 1 : kBitsWindow;
  static_assert(kBitsWindow % kProjectionBlock == 0);
  const PaddedRows rows(projection);
  const auto cols = std::size_t(projection.cols());
  TransportResult result;
  result.transfer.coefficients.resize(Eigen::Index(last - first), projection.cols());
  if (options.keep_hits) result.hits.resize(last - first);
  std::optional<RayCaster> own_caster;
  TransportOptions part_options = options;
  if (options.shadowed && !options.caster) part_options.caster = &own_caster.emplace(mesh);
  for (std::size_t begin = first, end;; begin = end) {  // at least once: an empty range's shapes
    end = std::min(last, (begin / window + 1) * window);
    part_options.first_vertex = begin;
    part_options.last_vertex = end;
    TransportResult part = trace_and_project(mesh, set, 0, nullptr, part_options, progress);
    if (cols > 0 && end > begin)
      visible_times_in_blocks(mesh, set, begin, end, part.visibility.words(0), rows,
                              result.transfer.coefficients.data() + (begin - first) * cols, cols);
    result.rays_cast += part.rays_cast;
    std::move(part.hits.begin(), part.hits.end(), result.hits.begin() + (begin - first));
    if (options.keep_visibility) result.visibility = std::move(part.visibility);  // one window
    if (end == last) break;
  }
  result.trace_seconds = clock.seconds();
  return result;
}

TransportResult diffuse_transfer(const Mesh& mesh, const DirectionSet& set, const Basis& basis,
                                 const TransportOptions& options, Progress* progress) {
  if (!basis.has_fast_projection(set))
    return diffuse_transfer(mesh, set, basis.projection_matrix(set), options, progress);
  auto project = [&](const std::uint32_t* vertices, std::size_t count,
                     const std::vector<std::uint64_t>& bits) -> Eigen::MatrixXf {
    const auto vertex_of = [vertices](std::size_t slot) { return vertices[slot]; };
    return basis.project(rows_from_bits(mesh, set, count, vertex_of, bits.data()), set)
        .cast<float>();
  };
  const BlockProjection projection = project;
  return trace_and_project(mesh, set, basis.size(), &projection, options, progress);
}

void transport_rows(const Mesh& mesh, const DirectionSet& set, const VisibilityBits& visibility,
                    std::size_t begin, std::size_t end, Eigen::MatrixXd& rows) {
  const auto vertex_of = [begin](std::size_t slot) { return std::uint32_t(begin + slot); };
  rows = rows_from_bits(mesh, set, end - begin, vertex_of, visibility.words(begin));
}

TransferSignal project_visibility(const Mesh& mesh, const DirectionSet& set,
                                  const VisibilityBits& visibility, const Basis& basis,
                                  std::size_t first_vertex) {
  const std::size_t count = visibility.vertices(), last = first_vertex + count;
  if (first_vertex > mesh.vertex_count() || count > mesh.vertex_count() - first_vertex ||
      visibility.directions() != static_cast<std::size_t>(set.size()))
    throw Error("project_visibility: visibility of " + std::to_string(count) + " vertices (from " +
                std::to_string(first_vertex) + ") x " + std::to_string(visibility.directions()) +
                " directions for a mesh of " + std::to_string(mesh.vertex_count()) + " and " +
                std::to_string(set.size()) + " directions");
  TransferSignal out;
  out.coefficients.resize(static_cast<Eigen::Index>(count), basis.size());
  // Blocks are counted from vertex 0 of the mesh, so a shard's rows are
  // those of the whole mesh's projection.
  if (!basis.has_fast_projection(set)) {
    // T P over the visible pairs only: the bake's own projection.
    const Eigen::MatrixXd projection = basis.projection_matrix(set);
    require_finite(projection, "the basis's projection matrix");
    if (count > 0 && basis.size() > 0)
      visible_times_in_blocks(mesh, set, first_vertex, last, visibility.words(0),
                              PaddedRows(projection), out.coefficients.data(),
                              std::size_t(basis.size()));
    return out;
  }
  // Fixed blocks: a GEMM's rows depend on the block's shape (row_blocks.hpp).
  for_each_row_block(first_vertex, last, kBlock, [&](std::size_t begin, std::size_t end) {
    const auto vertex_of = [begin](std::size_t slot) { return std::uint32_t(begin + slot); };
    const Eigen::MatrixXd rows =
        rows_from_bits(mesh, set, end - begin, vertex_of, visibility.words(begin - first_vertex));
    out.coefficients.middleRows(begin - first_vertex, end - begin) =
        basis.project(rows, set).cast<float>();
  });
  return out;
}

std::uint64_t trace_only(const Mesh& mesh, const DirectionSet& set, Progress* progress) {
  RayCaster caster(mesh);
  const auto s = static_cast<std::size_t>(set.size());
  const std::size_t words = VisibilityBits::words_for(s);
  const std::vector<float> dirs_f = to_float(set);
  const std::vector<std::uint32_t> order = morton_order(mesh);
  std::atomic<std::uint64_t> rays{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.vertex_count(), kBlock),
                    [&](const auto& range) {
                      std::vector<std::uint64_t> bits(range.size() * words);
                      const std::uint64_t cast = caster.trace_visibility(
                          mesh, &order[range.begin()], range.size(), dirs_f.data(), s, bits.data());
                      rays += cast;
                      if (progress) progress->add(double(range.size()), double(cast));
                    });
  return rays;
}

}  // namespace prt
