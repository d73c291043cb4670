// Checkpoints of long runs: a folder beside the output, ".NAME.checkpoint",
// holding the finished parts of a bake (vertex slabs of its transfer, a fitted
// basis) as files, each written whole (temporary, fsync, rename) so that a
// process killed at any moment leaves only complete parts. Rerunning the same
// command finds them and computes only what is missing; a changed scene or
// mesh is refused with a message. The folder is removed once the output is
// in place. Ranks of a distributed run share it (it is also how their parts
// reach the rank that writes the file).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "prt/part_keeper.hpp"
#include "prt/transfer.hpp"

namespace prt {

// 64-bit FNV-1a: a stable digest of what decides a result.
class Digest {
 public:
  Digest& add(const void* data, std::size_t bytes);
  Digest& add(const std::string& text);
  Digest& add_file(const std::filesystem::path& file);
  std::uint64_t value() const { return hash_; }
  std::string hex() const;

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

class CheckpointStore : public PartKeeper {
 public:
  // The folder for `output`, created when missing. `key` identifies the run
  // (a digest of the scene, mesh and plug-ins); `description` is written
  // beside it for people. A folder with another key throws prt::Error.
  // `exclusive`: hold the folder's lock while this object lives, refusing
  // a second process (a distributed run's other ranks share the first's).
  CheckpointStore(const std::filesystem::path& output, const std::string& key,
                  const std::string& description, bool exclusive = true);
  ~CheckpointStore() override;
  CheckpointStore(const CheckpointStore&) = delete;
  CheckpointStore& operator=(const CheckpointStore&) = delete;
  static std::filesystem::path folder_for(const std::filesystem::path& output);
  // Deletes the checkpoint of `output` (--restart), unless a process holds it.
  static void discard(const std::filesystem::path& output);

  const std::filesystem::path& folder() const { return folder_; }
  bool has(const std::string& name) const override;
  // Creates the empty marker `name` if no process has: true for the one
  // that did (O_EXCL; ranks share out work this way).
  bool claim(const std::string& name) const;
  // Parts are float, double or int32 matrices; saved whole or not at all.
  void save(const std::string& name, const MatrixXfRow& matrix) const override;
  void save(const std::string& name, const Eigen::MatrixXd& matrix) const override;
  void save(const std::string& name, const std::vector<std::int32_t>& values) const override;
  void save_text(const std::string& name, const std::string& text) const;
  std::string load_text(const std::string& name) const;
  MatrixXfRow load_floats(const std::string& name) const override;
  Eigen::MatrixXd load_doubles(const std::string& name) const override;
  std::vector<std::int32_t> load_ints(const std::string& name) const override;
  // Names of the parts present, sorted.
  std::vector<std::string> parts() const;
  // Deletes a part superseded by a later one (a bounce's state by the next's).
  void remove_part(const std::string& name) const override;
  std::string where() const override { return folder_.string(); }
  // Removes temporaries that killed processes left (".tmp-PID" files).
  void remove_temporaries() const;
  // Deletes the folder (after the output is in place).
  void remove() const;

 private:
  void open_key(const std::string& key, const std::string& description);
  std::filesystem::path folder_;
  int lock_ = -1;
};

}  // namespace prt
