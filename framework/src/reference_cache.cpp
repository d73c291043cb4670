// Reference files: "PRTREF1\n", the key (32 hex digits), vertices, samples
// and batches (64-bit), then radiance and standard error (v x 3 floats each).
#include "prt/reference_cache.hpp"

#include <xxhash.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {

namespace {

constexpr char kMagic[8] = {'P', 'R', 'T', 'R', 'E', 'F', '1', '\n'};
constexpr std::size_t kKeyChars = 32;

struct FileHeader {
  char magic[8];
  char key[kKeyChars];
  std::uint64_t vertices, samples, batches;
};

std::filesystem::path environment_path(const char* name) {
  const char* value = std::getenv(name);
  return value && *value ? std::filesystem::path(value) : std::filesystem::path();
}

}  // namespace

double Reference::noise_floor() const {
  if (standard_error.rows() == 0) return 0;
  return std::sqrt(standard_error.cast<double>().squaredNorm() / 3.0 /
                   double(standard_error.rows()));
}

struct ReferenceKey::State {
  XXH3_state_t* xxh = XXH3_createState();
};

ReferenceKey::ReferenceKey() : state_(std::make_unique<State>()) {
  if (!state_->xxh) throw Error("ReferenceKey: out of memory");
  XXH3_128bits_reset(state_->xxh);
}

ReferenceKey::~ReferenceKey() {
  XXH3_freeState(state_->xxh);
}

void ReferenceKey::add(const void* bytes, std::size_t size) {
  XXH3_128bits_update(state_->xxh, bytes, size);
}

void ReferenceKey::add(const std::string& text) {
  const std::uint64_t size = text.size();  // the length first: "ab"+"c" differs from "a"+"bc"
  add(&size, sizeof size);
  add(text.data(), text.size());
}

std::string ReferenceKey::hex() const {
  const XXH128_hash_t hash = XXH3_128bits_digest(state_->xxh);
  char text[kKeyChars + 1];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(hash.high64),
                static_cast<unsigned long long>(hash.low64));
  return text;
}

std::filesystem::path ReferenceCache::default_folder() {
  std::filesystem::path root = environment_path("PRT_CACHE_DIR");
  if (root.empty() && !(root = environment_path("XDG_CACHE_HOME")).empty()) root /= "prt";
  if (root.empty() && !(root = environment_path("HOME")).empty()) root = root / ".cache" / "prt";
  if (root.empty()) return {};
  return root / "ground-truth";
}

std::filesystem::path ReferenceCache::file(const std::string& key) const {
  return folder_ / (key + ".ref");
}

std::optional<Reference> ReferenceCache::load(const std::string& key, std::size_t vertices) const {
  if (folder_.empty()) return std::nullopt;
  std::ifstream in(file(key), std::ios::binary);
  if (!in) return std::nullopt;
  FileHeader header{};
  const auto rows = Eigen::Index(vertices);
  const std::streamsize body = std::streamsize(2 * 3 * sizeof(float) * vertices);
  in.seekg(0, std::ios::end);
  if (in.tellg() != std::streamoff(sizeof header + body)) return std::nullopt;
  in.seekg(0);
  in.read(reinterpret_cast<char*>(&header), sizeof header);
  if (!in || std::memcmp(header.magic, kMagic, sizeof kMagic) != 0 ||
      std::string(header.key, kKeyChars) != key || header.vertices != vertices ||
      header.batches < 1 || header.samples < header.batches)
    return std::nullopt;
  // Stored row-major (three floats a vertex), as Eigen's RowMajor maps it.
  using Rows = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  Rows radiance(rows, 3), error(rows, 3);
  in.read(reinterpret_cast<char*>(radiance.data()), body / 2);
  in.read(reinterpret_cast<char*>(error.data()), body / 2);
  if (!in || !radiance.allFinite() || !error.allFinite() || (error.array() < 0).any())
    return std::nullopt;
  Reference out;
  out.radiance = radiance;
  out.standard_error = error;
  out.samples = int(header.samples);
  out.batches = int(header.batches);
  out.cached = file(key);
  return out;
}

std::string ReferenceCache::store(const std::string& key, const Reference& reference) const {
  if (folder_.empty()) return "no cache folder ($PRT_CACHE_DIR, $XDG_CACHE_HOME and $HOME unset)";
  using Rows = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const Rows radiance = reference.radiance, error = reference.standard_error;
  FileHeader header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  std::memcpy(header.key, key.data(), std::min(key.size(), kKeyChars));
  header.vertices = std::uint64_t(radiance.rows());
  header.samples = std::uint64_t(reference.samples);
  header.batches = std::uint64_t(reference.batches);
  std::string bytes(reinterpret_cast<const char*>(&header), sizeof header);
  bytes.append(reinterpret_cast<const char*>(radiance.data()), sizeof(float) * radiance.size());
  bytes.append(reinterpret_cast<const char*>(error.data()), sizeof(float) * error.size());
  try {
    std::filesystem::create_directories(folder_);
    write_atomically(file(key), [&](const std::filesystem::path& temporary) {
      write_bytes_checked(temporary, bytes.data(), bytes.size(), file(key));
    });
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace prt
