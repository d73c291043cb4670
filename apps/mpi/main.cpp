// prt-mpi: the bake of `prt bake` with its vertices sharded across MPI ranks.
//   mpirun -np N prt-mpi bake scene.toml [-o out.h5]
// Every rank loads the scene and mesh and builds the ray-tracing structure,
// traces and projects its shard of vertices in slabs (kept in the output's
// checkpoint folder, which every rank must see), and compresses with the
// others (local assignment, sums over a fixed tree of segments); rank 0
// writes the file, equal to the one `prt bake` writes. docs/scale.md.
#include <mpi.h>
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "../common/bake_command.hpp"
#include "mpi_communicator.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"
#include "prt/memory.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"

namespace {

namespace fs = std::filesystem;

struct Args {
  prt::cli::BakeArgs bake;  // the budget is per rank
  bool quiet = false;
  int threads = 0;
};

// Each rank's peak memory and bytes received, and rank 0's report.
void report(const prt::BakeData& data, const prt::StageTimes& times,
            const prt::MpiCommunicator& comm, const std::filesystem::path& output) {
  using namespace prt;
  std::vector<double> peaks, received;  // per rank (received: before this exchange)
  const double mine_received = comm.bytes_received();
  for (const auto& p : allgather(comm, {peak_resident_bytes() / 1e9, mine_received})) {
    peaks.push_back(p[0]);
    received.push_back(p[1]);
  }
  if (comm.rank() != 0) return;
  std::cout << "baked " << data.receiver_count() << " "
            << (data.receivers.at_vertices() ? "vertices" : data.receivers.kind) << " x "
            << (data.streamed_transfer.rows ? data.streamed_transfer.cols
                                            : data.transfer.dimension())
            << " coefficients (" << data.basis.name << ", " << data.transport << ") on "
            << comm.size() << " ranks -> " << output.string() << "\n"
            << "rays cast: " << static_cast<std::uint64_t>(data.metrics.at("rays_cast")) << "\n";
  std::printf("peak memory per rank (GB):");
  for (double p : peaks) std::printf(" %.2f", p);
  std::printf(
      "\ncommunication (rank 0): %zu collectives, %.1f MB sent, %.1f MB received, %.2f s in MPI "
      "calls (waiting included)\n",
      comm.calls(), comm.bytes_sent() / 1e6, comm.bytes_received() / 1e6, comm.seconds());
  std::printf("received per rank (MB):");
  for (double r : received) std::printf(" %.1f", r / 1e6);
  std::printf("\n");
  std::cout << "timings (rank 0):\n" << times.table();
}

int bake(const Args& args, const prt::MpiCommunicator& comm) {
  using namespace prt;
  const bool root = comm.rank() == 0;
  Progress::set_enabled(root && !args.quiet);
  PluginRegistry registry(PluginRegistry::default_directories());
  const SceneSpec scene = SceneSpec::load(args.bake.scene, registry);
  StageTimes times;
  const BakePlan plan = plan_bake(scene, registry);
  BakeTarget target = cli::bake_target(scene, args.bake, "prt-mpi bake");
  target.description += " on " + std::to_string(comm.size()) + " ranks";
  RunOptions options = cli::bake_run_options(args.bake, !root || args.quiet);
  options.comm = &comm;
  if (!root) options.log = [](const std::string&) {};
  const BakeData data = bake_to_file(scene, plan, target, options, times);
  report(data, times, comm, target.file.path);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (provided < MPI_THREAD_FUNNELED) {  // TBB threads run beside the main thread's MPI calls
    if (rank == 0) std::cerr << "prt-mpi: this MPI library does not support threads\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  CLI::App app{
      "prt-mpi: prt bake with vertices sharded across MPI ranks (mpirun -np N prt-mpi bake ...)"};
  app.require_subcommand(1);
  Args args;
  app.add_flag("-q,--quiet", args.quiet, "no progress bars");
  auto* bake_cmd = prt::cli::add_bake_command(
      app, args.bake,
      "memory budget per rank, e.g. 8G (default: 3/4 of RAM); a larger shard of the transfer is "
      "kept on disk and compressed in passes",
      "compression keeps its state (each rank's labels, rank 0's means or models) in the "
      "checkpoint at most this often");
  bake_cmd->add_option("--threads", args.threads, "threads per rank (default: every core)")
      ->check(CLI::Range(1, 4096));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = rank == 0 ? app.exit(e) : (e.get_exit_code() == 0 ? 0 : 1);
    MPI_Finalize();
    return code;
  }
  int code = 0;
  try {
    std::optional<tbb::global_control> threads;
    if (args.threads > 0)
      threads.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(args.threads));
    prt::MpiCommunicator comm;
    code = bake(args, comm);
  } catch (...) {
    // One rank's error ends every rank: the others would wait for it forever.
    std::cerr << "prt-mpi: rank " << rank << ": " << prt::current_error_line() << "\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
  }
  MPI_Finalize();
  return code;
}
