// How a run reports and what it is given: progress, messages, checkpoints,
// ranks, memory budget; and the named timings of its stages.
#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "prt/checkpoint.hpp"
#include "prt/communicator.hpp"

namespace prt {

struct TransportResult;

// Named wall-clock timings of the stages of one run, in order.
struct StageTimes {
  std::vector<std::pair<std::string, double>> stages;
  void add(const std::string& name, double seconds) { stages.emplace_back(name, seconds); }
  // Another stage's times after these, in their order.
  void append(const StageTimes& later) {
    stages.insert(stages.end(), later.stages.begin(), later.stages.end());
  }
  std::string table() const;
};

struct TransportResult;
class RayCaster;

// How a run reports: progress bars (off when quiet) and one-line messages
// (summaries a user reads), through a callback the app provides.
struct RunOptions {
  bool quiet = false;  // no progress bars
  // Visibility bits (and hits, for bounces) traced before for the same mesh
  // and transport (trace_scene): bake() then casts no rays. Used by sweeps.
  const TransportResult* traced = nullptr;
  // false: the bake keeps the exact transfer as its compressed form (or the
  // basis's sparse approximation); a sweep compresses it later, many ways.
  bool compress = true;
  // Where this run's messages go; unset: the process's log sink (prt/log.hpp),
  // info only when not quiet.
  std::function<void(const std::string&)> log;
  // Finished parts are kept here and found again by a rerun (prt/checkpoint.hpp);
  // transfers each vertex gets alone are then computed in slabs of vertices
  // (slab_vertices rounded up to whole blocks of the projection,
  // kProjectionBlock, so that slabs change no bit of the rows).
  const CheckpointStore* checkpoint = nullptr;
  std::size_t slab_vertices = 65536;
  // Before the names of the parts a stage keeps: a bake of several channel
  // transfers runs the stages once per channel, each under its own prefix.
  std::string checkpoint_prefix;
  // Ranks of a distributed bake (prt-mpi); null: this process alone. Each
  // rank traces and compresses its shard of vertices; rank 0's result is the
  // whole bake, the other ranks' results are empty.
  const Communicator* comm = nullptr;
  // Bytes this bake aims to hold in memory (0: kDefaultMemoryFraction of
  // the machine's). A per-vertex transfer that would not fit beside the
  // mesh and its ray-tracing structure is kept in a file in the checkpoint
  // folder, and compressors read it in passes (prt/row_file.hpp).
  double memory_budget = 0;
  // How often a compressor keeps its state in the checkpoint (seconds).
  double checkpoint_seconds = 60;
  double budget() const;
  void message(const std::string& text) const;
  void warn(const std::string& text) const;
};

}  // namespace prt
