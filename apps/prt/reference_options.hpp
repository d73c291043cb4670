// The reference options of `prt render --compare`, `prt bench` and
// `prt compare-bases`, and how their noise floor is printed.
#pragma once
#include <memory>
#include <string>

#include "commands.hpp"
#include "prt/ground_truth.hpp"
#include "prt/reference_cache.hpp"
#include "prt/scene.hpp"

namespace prt::cli {

// The mean of a ground truth's batches and its noise: the RMS of the mean's
// standard error, relative to the mean's RMS.
std::pair<Eigen::MatrixX3f, double> mean_and_noise(const GroundTruthEstimate& truth);

// Share of rows whose error exceeds a quarter of the truth's RMS per row:
// the small artifacts a good RMS hides.
double far_off(const Eigen::MatrixX3f& estimate, const Eigen::MatrixX3f& truth);

// --samples N replaces the scene's [ground_truth] samples (checked as the scene's key is).
void apply_samples(const ReferenceArgs& args, SceneSpec& scene);

// The cache folder --cache names (default: ReferenceCache::default_folder()),
// or null with --no-cache.
std::unique_ptr<const ReferenceCache> reference_cache(const ReferenceArgs& args);

// Against a noisy reference E[rms^2] = error^2 + floor^2: an RMS within
// twice the floor is not resolved (the reference cannot rank it).
inline bool resolved(double rms, double floor) {
  return rms > 2 * floor;
}

// "noise floor 0.0021" and, when `rms` is within twice it, that the
// reference cannot tell this error from its own noise.
std::string noise_note(double rms, double floor);

// The line that says what the reference is and how sure: its samples,
// batches, per-vertex standard error, and what more samples would give.
std::string reference_summary(const Reference& reference);

}  // namespace prt::cli
