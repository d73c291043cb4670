#include "reference_options.hpp"

#include <cmath>
#include <cstdio>

namespace prt::cli {

std::pair<Eigen::MatrixX3f, double> mean_and_noise(const GroundTruthEstimate& truth) {
  const auto batches = double(truth.batches.size());
  Eigen::MatrixX3f mean = Eigen::MatrixX3f::Zero(truth.batches[0].rows(), 3);
  for (const auto& batch : truth.batches) mean += batch / float(batches);
  double spread = 0;
  for (const auto& batch : truth.batches)
    spread += (batch - mean).cast<double>().squaredNorm() / (batches * (batches - 1));
  return {mean, std::sqrt(spread) / std::max(1e-30, mean.cast<double>().norm())};
}

double far_off(const Eigen::MatrixX3f& estimate, const Eigen::MatrixX3f& truth) {
  const double limit = 0.25 * truth.cast<double>().norm() / std::sqrt(double(truth.rows()));
  Eigen::Index count = 0;
  for (Eigen::Index v = 0; v < truth.rows(); ++v)
    count += (estimate.row(v) - truth.row(v)).cast<double>().norm() > limit;
  return truth.rows() ? double(count) / double(truth.rows()) : 0.0;
}

void apply_samples(const ReferenceArgs& args, SceneSpec& scene) {
  if (args.samples == 0) return;
  // Its range is [ground_truth] samples' range, checked by the command line.
  scene.ground_truth.set(keys::ground_truth::samples.name(), args.samples,
                         SourceLocation{"--samples"});
}

std::unique_ptr<const ReferenceCache> reference_cache(const ReferenceArgs& args) {
  if (args.no_cache) return nullptr;
  return std::make_unique<const ReferenceCache>(
      args.cache.empty() ? ReferenceCache::default_folder() : std::filesystem::path(args.cache));
}

std::string noise_note(double rms, double floor) {
  char text[200];
  if (floor > 0 && !resolved(rms, floor))
    std::snprintf(text, sizeof text,
                  "noise floor %.4g: NOT RESOLVED, within twice the reference's own noise "
                  "(raise --samples)",
                  floor);
  else
    std::snprintf(text, sizeof text, "noise floor %.4g", floor);
  return text;
}

std::string reference_summary(const Reference& reference) {
  const double floor = reference.noise_floor();
  const double radiance_rms = reference.radiance.rows()
                                  ? std::sqrt(reference.radiance.cast<double>().squaredNorm() /
                                              3.0 / double(reference.radiance.rows()))
                                  : 0.0;
  char text[400];
  std::snprintf(text, sizeof text,
                "ground truth: %d samples per vertex in %d independent batches%s; Monte Carlo "
                "standard error per vertex: RMS %.4g (%.3g%% of the radiance's RMS), the noise "
                "floor of every RMS below; --samples %d would at least halve it",
                reference.samples, reference.batches,
                reference.cached.empty() ? "" : " (reused from the cache)", floor,
                radiance_rms > 0 ? 100 * floor / radiance_rms : 0.0, 4 * reference.samples);
  return text;
}

}  // namespace prt::cli
