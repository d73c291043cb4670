// The bake command's options, shared by prt and prt-mpi so that both take the
// same flags with the same checks, and what they make of them (the target of
// bake_to_file and the run's options).
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <string>

#include "prt/bake.hpp"

namespace prt::cli {

struct BakeArgs {
  std::string scene, output;
  bool force = false;                 // replace an existing output of another kind
  bool restart = false;               // discard a checkpoint left by an earlier run
  std::size_t slab_vertices = 65536;  // vertices per checkpointed slab
  std::uint64_t memory = 0;           // memory budget in bytes (0: the default share of RAM)
  double checkpoint_seconds = 60;     // how often compression keeps its state
};

// `memory_help` and `checkpoint_help` say what the budget and the kept state
// are per (a process, or each rank).
inline CLI::App* add_bake_command(CLI::App& app, BakeArgs& args, const std::string& memory_help,
                                  const std::string& checkpoint_help) {
  auto* command = app.add_subcommand("bake", "trace, project and compress a scene's transfer");
  command->add_option("scene", args.scene, "scene description (.toml)")->required();
  command->add_option("-o,--output", args.output, "bake file (default: from the scene)");
  command->add_flag("--force", args.force,
                    "replace an existing output file of another kind (never an input)");
  command->add_flag("--restart", args.restart,
                    "discard the checkpoint an interrupted run left (default: resume from it)");
  command
      ->add_option("--slab-vertices", args.slab_vertices,
                   "vertices traced per checkpointed slab, rounded up to a multiple of 256 for a "
                   "per-vertex transfer (a killed bake loses at most one)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t(1), std::size_t(1) << 40));
  command->add_option("--memory", args.memory, memory_help)
      ->transform(CLI::AsSizeValue(false))
      ->check(CLI::Range(std::uint64_t(1) << 20, std::uint64_t(1) << 50));
  command->add_option("--checkpoint-seconds", args.checkpoint_seconds, checkpoint_help)
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));
  return command;
}

// `who` leads the description kept in the checkpoint folder ("prt bake").
inline BakeTarget bake_target(const SceneSpec& scene, const BakeArgs& args,
                              const std::string& who) {
  const std::filesystem::path output =
      args.output.empty() ? scene.bake_path() : std::filesystem::path(args.output);
  return {{output, FileKind::bake, "bake file", args.output.empty()},
          args.force,
          args.restart,
          who + " " + scene.file.string() + " -> " + output.string()};
}

inline RunOptions bake_run_options(const BakeArgs& args, bool quiet) {
  RunOptions options{quiet};
  options.slab_vertices = args.slab_vertices;
  options.memory_budget = double(args.memory);
  options.checkpoint_seconds = args.checkpoint_seconds;
  return options;
}

}  // namespace prt::cli
