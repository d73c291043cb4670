// Transport sampling with Embree: per-vertex visibility over a direction set,
// kept as bits, and the projection of cosine-weighted visibility.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Progress;

// One bit per (vertex, direction): 1 = the ray escapes (unoccluded).
class VisibilityBits {
 public:
  VisibilityBits() = default;
  static std::size_t words_for(std::size_t directions) { return (directions + 63) / 64; }
  VisibilityBits(std::size_t vertices, std::size_t directions)
      : directions_(directions),
        words_per_vertex_((directions + 63) / 64),
        bits_(vertices * words_per_vertex_, 0) {}
  bool get(std::size_t vertex, std::size_t direction) const {
    return (bits_[vertex * words_per_vertex_ + direction / 64] >> (direction % 64)) & 1u;
  }
  void set(std::size_t vertex, std::size_t direction) {
    bits_[vertex * words_per_vertex_ + direction / 64] |= std::uint64_t(1) << (direction % 64);
  }
  std::size_t directions() const { return directions_; }
  std::size_t vertices() const { return words_per_vertex_ ? bits_.size() / words_per_vertex_ : 0; }
  std::size_t count_visible(std::size_t vertex) const;
  std::uint64_t* words(std::size_t vertex) { return bits_.data() + vertex * words_per_vertex_; }
  const std::uint64_t* words(std::size_t vertex) const {
    return bits_.data() + vertex * words_per_vertex_;
  }

 private:
  std::size_t directions_ = 0, words_per_vertex_ = 0;
  std::vector<std::uint64_t> bits_;
};

// A ray that hit the front of a triangle (the side its vertex normals face):
// the direction's index in the set, the triangle and Embree's barycentrics,
// point = (1 - u - v) a + u b + v c. Back-face hits carry no light.
struct SurfaceHit {
  std::uint32_t direction = 0, triangle = 0;
  float u = 0, v = 0;
};
using HitLists = std::vector<std::vector<SurfaceHit>>;  // per vertex

// Embree device + scene over a mesh; shared by bake, ground truth and benchmarks.
class RayCaster {
 public:
  explicit RayCaster(const Mesh& mesh);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  // Origin offset (world units) that keeps rays off their own surface.
  float offset() const { return offset_; }
  // True where the ray from origin toward direction hits nothing (within
  // `far`, per ray, when given: the distance to a light). Batched through
  // Embree's stream API.
  void occluded(const float* origins, const float* directions, std::size_t count,
                std::uint8_t* escaped, const float* far = nullptr) const;

  // First hits: `triangle` gets the hit triangle or -1 where the ray escapes
  // or hits a back face; u, v the barycentrics; `escaped` (optional) 1 where
  // the ray hit nothing at all.
  void intersect(const Mesh& mesh, const float* origins, const float* directions, std::size_t count,
                 std::int64_t* triangle, float* u, float* v, std::uint8_t* escaped = nullptr) const;

  // Visibility of `count` vertices over `s` directions (xyz floats): for each
  // vertex, bits of (s + 63) / 64 words; a bit is set where the direction lies
  // above the tangent plane and its ray escapes. Rays go straight into
  // Embree's stream, with no intermediate arrays. With `hits` (one list per
  // vertex slot), blocked rays are intersected instead and their front-face
  // hits recorded, for inter-reflection. Returns the rays cast.
  // `direction_stride` > 0: each vertex slot has its own s directions, slot
  // i's from directions + i * direction_stride floats (the ground truth's
  // per-vertex samples); 0: all share one set.
  std::uint64_t trace_visibility(const Mesh& mesh, const std::uint32_t* vertices, std::size_t count,
                                 const float* directions, std::size_t s, std::uint64_t* bits,
                                 std::vector<SurfaceHit>* hits = nullptr,
                                 std::size_t direction_stride = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  float offset_ = 1e-4f;
};

struct TransportOptions {
  bool shadowed = true;  // false: unshadowed transfer (no rays cast)
  bool keep_visibility = false;
  bool keep_hits = false;  // record front-face hits of blocked rays (inter-reflection)
  // Only vertices [first_vertex, last_vertex) (a slab of a streamed or
  // distributed bake): the result's rows, bits and hits are theirs, in order.
  std::size_t first_vertex = 0, last_vertex = static_cast<std::size_t>(-1);
  // The mesh's ray caster, built once for many slabs; null: built here.
  const RayCaster* caster = nullptr;
};

struct TransportResult {
  TransferSignal transfer;    // v x n, (1/pi) int V max(n.s, 0) y(s) ds
  VisibilityBits visibility;  // when keep_visibility
  HitLists hits;              // when keep_hits
  std::uint64_t rays_cast = 0;
  double trace_seconds = 0;  // wall time of the trace and the projection
};

// Vertices whose visibility bits diffuse_transfer holds at once when it does
// not keep them: a window of the mesh's grid (50 MB at 6,144 directions).
constexpr std::size_t kBitsWindow = 65536;

// Diffuse transfer per vertex: traces only directions above the tangent plane
// (a window of kBitsWindow vertices at a time, unless the bits are kept),
// then projects each vertex's cosine-weighted visibility onto the basis's
// projection matrix P (s x n) along trees of neighbours
// (visible_times_in_blocks). Multithreaded with TBB; results do not depend
// on the thread count, nor on a range whose ends are multiples of
// kProjectionBlock.
TransportResult diffuse_transfer(const Mesh& mesh, const DirectionSet& directions,
                                 const Eigen::MatrixXd& projection, const TransportOptions& options,
                                 Progress* progress);

// Vertex indices sorted along a Morton curve of their positions, so that a
// block of consecutive vertices traces rays through the same part of the BVH.
// Only vertices [first, last), ordered by their place in the whole mesh's curve.
std::vector<std::uint32_t> morton_order(const Mesh& mesh, std::size_t first = 0,
                                        std::size_t last = static_cast<std::size_t>(-1));

// The same through a basis: its fast projection when it has one for `set`,
// otherwise its projection matrix.
class Basis;
TransportResult diffuse_transfer(const Mesh& mesh, const DirectionSet& directions,
                                 const Basis& basis, const TransportOptions& options,
                                 Progress* progress);

// Cosine-weighted visibility / pi of vertices [begin, end) over the set, from
// stored visibility bits: rows of the v x s transport matrix.
void transport_rows(const Mesh& mesh, const DirectionSet& directions,
                    const VisibilityBits& visibility, std::size_t begin, std::size_t end,
                    Eigen::MatrixXd& rows);

// Diffuse transfer from stored visibility (no rays): used after fitting a
// data-driven basis to the same visibility. The bits' rows are the mesh's
// vertices from `first_vertex` on (a rank's shard; default all).
TransferSignal project_visibility(const Mesh& mesh, const DirectionSet& directions,
                                  const VisibilityBits& visibility, const Basis& basis,
                                  std::size_t first_vertex = 0);

// Traces exactly the rays diffuse_transfer would, and nothing else: the
// yardstick of the bake benchmark.
std::uint64_t trace_only(const Mesh& mesh, const DirectionSet& directions, Progress* progress);

// True where a ray along `direction` meets the side of triangle `t` that its
// vertex normals face (interpolated at u, v).
bool front_face(const Mesh& mesh, std::uint32_t t, float u, float v,
                const Eigen::Vector3f& direction);

}  // namespace prt
