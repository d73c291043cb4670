// The Monte Carlo ground truth of a scene as per-vertex radiance and as an
// image, and per-vertex error statistics against it.
#pragma once
#include "prt/environment.hpp"
#include "prt/reference_cache.hpp"
#include "prt/relighting.hpp"

namespace prt {

// The Monte Carlo ground truth per vertex (v x 3, albedo included) under
// `lighting` (the scene's map, or its band-limited reconstruction), toward
// the camera for glossy materials, with its standard error: [ground_truth]
// samples per vertex in four independent batches, reused from `cache` when
// it holds the same reference and kept there when not.
Reference reference_radiance(const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
                             const Camera& camera, const RunOptions& options,
                             const ReferenceCache* cache = nullptr);
// reference_radiance's radiance alone, never cached.
Eigen::MatrixX3f ground_truth_vertices(const SceneSpec& scene, const Mesh& mesh,
                                       const Environment& lighting, const Camera& camera,
                                       const RunOptions& options);
// Renders the Monte Carlo ground truth with the scene's renderer, under the
// scene's light or `lighting` when given.
Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times,
                             const Environment* lighting = nullptr,
                             const ReferenceCache* cache = nullptr);
// Per-vertex radiance drawn by the scene's renderer from its camera, over
// `background`.
Image render_reference(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                       const Eigen::MatrixX3f& radiance, const Environment& background);

// Per-vertex error statistics of `approximation` against `reference` (v x 3).
struct ErrorStats {
  double rms = 0, relative_rms = 0, p99 = 0, max = 0;
};
ErrorStats vertex_error(const Eigen::MatrixX3f& approximation, const Eigen::MatrixX3f& reference);

// The ground truth under the light basis's reconstruction of `light` (the
// environment band-limited by the basis): what the basis can carry at all.
Reference band_limited_truth(const SceneSpec& scene, const Mesh& mesh, const Relighting& relighting,
                             const Environment& environment, const Eigen::MatrixX3d& light,
                             const Camera& camera, const RunOptions& options,
                             const ReferenceCache* cache = nullptr);

// A relit bake's error against the ground truth in three parts (per-vertex
// RMS): light truncation (band-limited truth against the full truth),
// transfer projection (the exact transfer relit against the band-limited
// truth) and compression (the compressed transfer against the exact one);
// total is the compressed transfer against the full truth.
struct ErrorBudget {
  double truncation = 0, projection = 0, compression = 0, total = 0;
};
ErrorBudget error_budget(const Eigen::MatrixX3f& truth, const Eigen::MatrixX3f& band_limited,
                         const Eigen::MatrixX3f& exact, const Eigen::MatrixX3f& compressed);

}  // namespace prt
