// A scene baked: plan -> rays -> transfer -> compression, as BakeData, and
// the one driver that bakes a plan into a file (prt bake, prt-mpi, Python).
#pragma once
#include <filesystem>
#include <string>

#include "prt/bake_file.hpp"
#include "prt/bake_plan.hpp"
#include "prt/output_file.hpp"
#include "prt/registry.hpp"
#include "prt/run_options.hpp"
#include "prt/scene.hpp"
#include "prt/transport.hpp"

namespace prt {

// Traces the scene's mesh over its direction set, keeping the visibility
// bits, and the hits when the scene asks for bounces.
TransportResult trace_scene(const SceneSpec& scene, const RunOptions& options);

// plan -> rays -> transfer -> compression, as BakeData. Fills times per stage.
// `plan` is plan_bake(scene, ...): made once by the caller, it is not remade.
BakeData bake(const SceneSpec& scene, const BakePlan& plan, const RunOptions& options,
              StageTimes& times);
// The same, planning first ("load plug-ins" in times).
BakeData bake(const SceneSpec& scene, PluginRegistry& registry, const RunOptions& options,
              StageTimes& times);

// Where bake_to_file writes, and how.
struct BakeTarget {
  OutputRequest file;       // checked before any work (check_output)
  bool force = false;       // replace a file that is not a bake
  bool restart = false;     // discard a kept checkpoint first
  std::string description;  // who bakes what, written in the checkpoint folder
};

// Bakes `plan` into `target.file.path` through a checkpoint folder beside it:
// the finished parts are kept as they come, a rerun after a kill resumes from
// them, and the folder goes once the file is in place (nothing is left when
// the bake fails before keeping a part). With options.comm, every rank calls
// it: rank 0 checks the output, opens the folder and writes the file; the
// others share the folder. Returns rank 0's BakeData (an empty one on other
// ranks); `options.checkpoint` is set here.
BakeData bake_to_file(const SceneSpec& scene, const BakePlan& plan, const BakeTarget& target,
                      RunOptions options, StageTimes& times);

}  // namespace prt
