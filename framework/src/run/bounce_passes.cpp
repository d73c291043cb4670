#include "prt/bounce_passes.hpp"

#include <algorithm>

#include "prt/checkpoint.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "slab_parts.hpp"

namespace prt {

namespace {

// The parts of the state after bounce b: the bounce itself (the next one's
// input), the running total and the norms so far; the marker is written
// last, so a kill between the writes leaves the previous state whole.
std::string marker_of(const BounceCheckpoint& c, int b) {
  return c.prefix + "bounce-" + std::to_string(b);
}
std::string part_of(const BounceCheckpoint& c, int b, const char* what) {
  return marker_of(c, b) + "." + what;
}

void keep_state(const BounceCheckpoint& c, int b, const MatrixXfRow& previous,
                const BouncedTransfer& out) {
  const CheckpointStore& store = *c.store;
  store.save(part_of(c, b, "previous"), previous);
  store.save(part_of(c, b, "total"), out.total);
  store.save(part_of(c, b, "norms"), Eigen::MatrixXd(Eigen::Map<const Eigen::RowVectorXd>(
                                         out.bounce_norms.data(), Eigen::Index(b))));
  store.save_text(marker_of(c, b), std::to_string(b));
  for (const std::string& part : store.parts())  // this bounce's slabs: in the state now
    if (part.rfind(marker_of(c, b) + ".rows-", 0) == 0) store.remove_part(part);
  if (b > 1) {  // superseded: a bounce's state is as large as the transfer
    store.remove_part(marker_of(c, b - 1));
    for (const char* what : {"previous", "total", "norms"})
      store.remove_part(part_of(c, b - 1, what));
  }
}

// Bounce b's rows, slab by slab: kept slabs are loaded, the others gathered
// and kept.
MatrixXfRow bounce_in_slabs(const BounceCheckpoint& c, int b, const MatrixXfRow& previous,
                            const BounceFunction& bounce) {
  return rows_in_slabs(
      *c.store, marker_of(c, b), std::size_t(previous.rows()), previous.cols(), c.slab_vertices,
      [&](const SlabRange& slab) { return bounce(previous, slab.first, slab.last); },
      "bounce " + std::to_string(b), c.message, {}, SlabSharing{c.comm});
}

// The last bounce kept (0: none), its state loaded into previous and out.
int load_state(const BounceCheckpoint& c, int bounces, const MatrixXfRow& direct,
               MatrixXfRow& previous, BouncedTransfer& out) {
  const CheckpointStore& store = *c.store;
  for (int b = bounces; b >= 1; --b) {
    if (!store.has(marker_of(c, b))) continue;
    previous = store.load_floats(part_of(c, b, "previous"));
    out.total = store.load_floats(part_of(c, b, "total"));
    const Eigen::MatrixXd norms = store.load_doubles(part_of(c, b, "norms"));
    if (previous.rows() != direct.rows() || previous.cols() != direct.cols() ||
        out.total.rows() != direct.rows() || out.total.cols() != direct.cols() || norms.size() != b)
      throw Error(store.folder().string() + "/" + marker_of(c, b) +
                  ": the kept bounce does not match the transfer (" +
                  std::to_string(previous.rows()) + " x " + std::to_string(previous.cols()) +
                  " for " + std::to_string(direct.rows()) + " x " + std::to_string(direct.cols()) +
                  "); delete the folder or rerun with --restart");
    out.bounce_norms.assign(norms.data(), norms.data() + b);
    return b;
  }
  return 0;
}

}  // namespace

BouncedTransfer bounce_passes(const MatrixXfRow& direct, int bounces, const BounceFunction& bounce,
                              Progress* progress, const BounceCheckpoint& checkpoint) {
  BouncedTransfer out{direct, {}};
  MatrixXfRow previous = direct;
  int done = 0;
  if (checkpoint.store) {
    done = load_state(checkpoint, bounces, direct, previous, out);
    if (done > 0 && checkpoint.message)
      checkpoint.message(
          "resuming: inter-reflection" +
          (checkpoint.prefix.empty()
               ? std::string()
               : " (" + checkpoint.prefix.substr(0, checkpoint.prefix.size() - 1) + ")") +
          " after bounce " + std::to_string(done) + " of " + std::to_string(bounces));
    if (progress) progress->add(double(done));
  }
  for (int b = done; b < bounces; ++b) {
    previous = checkpoint.store ? bounce_in_slabs(checkpoint, b + 1, previous, bounce)
                                : bounce(previous, 0, std::size_t(previous.rows()));
    out.total += previous;
    out.bounce_norms.push_back(previous.cast<double>().norm());
    if (checkpoint.store && SlabSharing{checkpoint.comm}.root())
      keep_state(checkpoint, b + 1, previous, out);
    if (progress) progress->add(1.0);
  }
  return out;
}

}  // namespace prt
