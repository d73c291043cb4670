#include "slab_parts.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace prt {

std::vector<SlabRange> slabs_of(std::size_t first, std::size_t last, std::size_t slab) {
  std::vector<SlabRange> out;
  for (std::size_t k = first / slab; k * slab < last; ++k)
    out.push_back({std::max(first, k * slab), std::min(last, (k + 1) * slab)});
  return out;
}

std::string rows_name(const char* what, std::size_t first, std::size_t last) {
  char name[96];
  std::snprintf(name, sizeof name, "%s.rows-%012zu-%012zu", what, first, last);
  return name;
}

Error misshapen_part(const CheckpointStore& store, const std::string& name,
                     const std::string& holds, const std::string& needs) {
  return Error(store.folder().string() + "/" + name + ": holds " + holds +
               " where the slab needs " + needs + "; delete the folder or rerun with --restart");
}

MatrixXfRow kept_rows(const CheckpointStore& store, const SlabRange& slab, Eigen::Index cols,
                      const char* what) {
  const std::string name = rows_name(what, slab);
  MatrixXfRow rows = store.load_floats(name);
  if (rows.rows() != static_cast<Eigen::Index>(slab.size()) || rows.cols() != cols)
    throw misshapen_part(
        store, name,
        "a " + std::to_string(rows.rows()) + " x " + std::to_string(rows.cols()) + " part",
        std::to_string(slab.size()) + " x " + std::to_string(cols));
  return rows;
}

void keep_count(const CheckpointStore& store, const char* what, const SlabRange& slab,
                std::uint64_t count) {
  store.save(rows_name(what, slab),
             Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, double(count))));
}

std::uint64_t kept_count(const CheckpointStore& store, const char* what, const SlabRange& slab) {
  return static_cast<std::uint64_t>(store.load_doubles(rows_name(what, slab))(0, 0));
}

void keep_bits(const CheckpointStore& store, const char* what, const SlabRange& slab,
               const VisibilityBits& bits) {
  // Each 64-bit word as two int32 values (the store's integer parts).
  std::vector<std::int32_t> saved(2 * slab.size() * VisibilityBits::words_for(bits.directions()));
  if (!saved.empty()) std::memcpy(saved.data(), bits.words(0), saved.size() * sizeof(std::int32_t));
  store.save(rows_name(what, slab), saved);
}

void copy_kept_bits(const CheckpointStore& store, const SlabRange& slab, const SlabRange& range,
                    std::size_t words, VisibilityBits& bits, const char* what) {
  const std::string name = rows_name(what, slab);
  const std::vector<std::int32_t> saved = store.load_ints(name);
  if (saved.size() != 2 * slab.size() * words)
    throw misshapen_part(store, name, std::to_string(saved.size()) + " values",
                         std::to_string(2 * slab.size() * words));
  const std::size_t first = std::max(slab.first, range.first),
                    last = std::min(slab.last, range.last);
  if (first < last)
    std::memcpy(bits.words(first - range.first), &saved[2 * (first - slab.first) * words],
                (last - first) * words * sizeof(std::uint64_t));
}

std::size_t say_kept_slabs(const CheckpointStore& store, const std::vector<SlabRange>& slabs,
                           const std::function<bool(const SlabRange&)>& kept,
                           const std::string& label,
                           const std::function<void(const std::string&)>& message) {
  const auto count = std::count_if(slabs.begin(), slabs.end(), kept);
  if (count > 0 && message)
    message("resuming: " + std::to_string(count) + " of " + std::to_string(slabs.size()) +
            " slabs of " + label + " kept in " + store.folder().string());
  return std::size_t(count);
}

MatrixXfRow rows_in_slabs(const CheckpointStore& store, const std::string& what,
                          std::size_t vertices, Eigen::Index cols, std::size_t slab_vertices,
                          const std::function<MatrixXfRow(const SlabRange&)>& compute,
                          const std::string& label,
                          const std::function<void(const std::string&)>& message,
                          const std::function<void(const SlabRange&)>& on_kept,
                          SlabSharing sharing) {
  const auto slabs = slabs_of(0, vertices, std::max<std::size_t>(1, slab_vertices));
  say_kept_slabs(
      store, slabs, [&](const SlabRange& slab) { return store.has(rows_name(what.c_str(), slab)); },
      label, message);
  MatrixXfRow out(Eigen::Index(vertices), cols);
  // Each slab is computed once (kept slabs of a killed run are not), then
  // the others are read from the checkpoint.
  std::vector<bool> here(slabs.size(), false);
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    const SlabRange& slab = slabs[i];
    if (!sharing.mine(i) || store.has(rows_name(what.c_str(), slab))) continue;
    const MatrixXfRow rows = compute(slab);
    store.save(rows_name(what.c_str(), slab), rows);
    out.middleRows(Eigen::Index(slab.first), Eigen::Index(slab.size())) = rows;
    here[i] = true;
  }
  sharing.barrier();  // every slab is kept
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    if (here[i]) continue;
    const SlabRange& slab = slabs[i];
    out.middleRows(Eigen::Index(slab.first), Eigen::Index(slab.size())) =
        kept_rows(store, slab, cols, what.c_str());
    if (on_kept) on_kept(slab);
  }
  sharing.barrier();  // every rank has read them: a caller may now replace them
  return out;
}

}  // namespace prt
