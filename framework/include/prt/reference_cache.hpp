// Monte Carlo references kept on disk: per-vertex radiance and its standard
// error, keyed by a hash of everything they depend on (mesh, material,
// light, rotation, samples, seed, camera for glossy materials), so a second
// `prt render --compare`, a sweep or a bench reuses them instead of tracing.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace prt {

// The ground truth of a scene with its Monte Carlo error bar: the mean of
// `batches` independent estimates (batch means), and per vertex and channel
// the standard error of that mean (zero when there is one batch).
struct Reference {
  Eigen::MatrixX3f radiance;        // v x 3, albedo included
  Eigen::MatrixX3f standard_error;  // v x 3
  int samples = 0, batches = 1;     // samples per vertex in all, in `batches` runs
  std::filesystem::path cached;     // the cache file it was read from, if any
  // The per-vertex RMS of the standard error, in vertex_error's norm: an
  // RMS against this reference below about this is not resolved by it.
  double noise_floor() const;
};

// A 128-bit hash of the bytes it is given (xxHash's XXH3), as 32 hex digits.
class ReferenceKey {
 public:
  ReferenceKey();
  ~ReferenceKey();
  ReferenceKey(const ReferenceKey&) = delete;
  ReferenceKey& operator=(const ReferenceKey&) = delete;
  void add(const void* bytes, std::size_t size);
  void add(const std::string& text);
  void add(double value) { add(&value, sizeof value); }
  std::string hex() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// A folder of references, one file per key. Reading is careful (a file of
// the wrong size or with a non-finite value is ignored and recomputed);
// writing is atomic and best effort (a full disk costs only the reuse).
class ReferenceCache {
 public:
  explicit ReferenceCache(std::filesystem::path folder) : folder_(std::move(folder)) {}
  // $PRT_CACHE_DIR, else $XDG_CACHE_HOME/prt, else ~/.cache/prt (then
  // "ground-truth" under it).
  static std::filesystem::path default_folder();
  std::filesystem::path file(const std::string& key) const;
  std::optional<Reference> load(const std::string& key, std::size_t vertices) const;
  // Returns "" or why the reference was not kept.
  std::string store(const std::string& key, const Reference& reference) const;

 private:
  std::filesystem::path folder_;
};

}  // namespace prt
