// The bake and view pipelines composed from a scene: the same code serves the
// CLI, the tests and the benchmarks.
#pragma once
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/compressor.hpp"
#include "prt/image.hpp"
#include "prt/registry.hpp"
#include "prt/renderer.hpp"
#include "prt/scene.hpp"

namespace prt {

// Named wall-clock timings of the stages of one run, in order.
struct StageTimes {
  std::vector<std::pair<std::string, double>> stages;
  void add(const std::string& name, double seconds) { stages.emplace_back(name, seconds); }
  std::string table() const;
};

struct TransportResult;

struct RunOptions {
  bool quiet = false;  // no progress bars
  // Visibility bits (and hits, for bounces) traced before for the same mesh
  // and transport (trace_scene): bake() then casts no rays. Used by sweeps.
  const TransportResult* traced = nullptr;
};

// Traces the scene's mesh over its direction set, keeping the visibility
// bits, and the hits when the scene asks for bounces.
TransportResult trace_scene(const SceneSpec& scene, const RunOptions& options);

// Mesh -> rays -> projection -> compression. Fills times per stage.
BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times);

// Writes a compression report into bake-file metrics.
void record(const CompressionReport& report, std::map<std::string, double>& metrics);

// Checks that `data` was baked with the scene's basis and parameters.
void check_bake_matches(const BakeData& data, const SceneSpec& scene);
// Throws unless the bake's transfer has one column per basis coefficient (per
// exit-basis row for glossy transfer): a file's shape must fit its plug-ins.
void check_bake_dimension(const BakeData& data, const Basis& basis);

struct Rendered {
  Image image;
  Eigen::MatrixX3f vertex_radiance;          // v x 3 including albedo
  std::map<std::string, double> statistics;  // the renderer's (overdraw, draw time, ...)
};

// One relighting of a bake's transfer (its compressed form or another encoding
// of it) for a light vector and camera: per-vertex exit coefficients, glossy
// frames and the radiance each vertex sends to the camera (albedo included).
struct Relit {
  MatrixXfRow exit_coefficients;  // v x 3 N_r
  std::vector<Frame> frames;      // glossy only
  Eigen::MatrixX3f vertex_radiance;
};
// `frames` (glossy): the mesh's tangent frames when the caller keeps them.
Relit relight_view(const BakeData& data, const CompressedTransfer& transfer,
                   const Eigen::MatrixX3d& light, const Camera& camera,
                   const std::vector<Frame>* frames = nullptr);
// The renderer's input for it; points into `data`, `transfer` and `relit`.
RenderInput render_input(const BakeData& data, const CompressedTransfer& transfer,
                         const Relit& relit, const Eigen::MatrixX3d& light, const Camera& camera);

// Light projection -> per-cluster constants -> per-vertex sums -> image.
Rendered render(const SceneSpec& scene, const BakeData& data, PluginRegistry& registry,
                StageTimes& times);

// Renders the Monte Carlo ground truth with the scene's renderer.
Rendered render_ground_truth(const SceneSpec& scene, const Mesh& mesh, PluginRegistry& registry,
                             const RunOptions& options, StageTimes& times);

// Per-vertex error statistics of `approximation` against `reference` (v x 3).
struct ErrorStats {
  double rms = 0, relative_rms = 0, p99 = 0, max = 0;
};
ErrorStats vertex_error(const Eigen::MatrixX3f& approximation, const Eigen::MatrixX3f& reference);

}  // namespace prt
