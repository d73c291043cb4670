// prt: bake, render and inspect precomputed radiance transfer.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "commands.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"

namespace {
const char* kForceHelp = "replace an existing output file of another kind (never an input)";
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"prt: precomputed radiance transfer with plug-in bases, compressors and renderers"};
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "no progress bars");

  prt::cli::BakeArgs bake;
  auto* bake_cmd = app.add_subcommand("bake", "trace, project and compress a scene's transfer");
  bake_cmd->add_option("scene", bake.scene, "scene description (.toml)")->required();
  bake_cmd->add_option("-o,--output", bake.output, "bake file (default: from the scene)");
  bake_cmd->add_flag("--force", bake.force, kForceHelp);
  bake_cmd->add_flag("--restart", bake.restart,
                     "discard the checkpoint an interrupted run left (default: resume from it)");
  bake_cmd
      ->add_option("--slab-vertices", bake.slab_vertices,
                   "vertices traced per checkpointed slab, rounded up to a multiple of 256 for a "
                   "per-vertex transfer (a killed bake loses at most one)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t(1), std::size_t(1) << 40));
  bake_cmd
      ->add_option("--memory", bake.memory,
                   "memory budget, e.g. 8G or 512M (default: 3/4 of RAM); a larger transfer is "
                   "kept on disk and compressed in passes")
      ->transform(CLI::AsSizeValue(false))
      ->check(CLI::Range(std::uint64_t(1) << 20, std::uint64_t(1) << 50));

  bake_cmd
      ->add_option("--checkpoint-seconds", bake.checkpoint_seconds,
                   "compression keeps its state in the checkpoint at most this often")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));

  prt::cli::RenderArgs render;
  auto* render_cmd = app.add_subcommand("render", "relight a bake and write an image");
  render_cmd->add_option("scene", render.scene, "scene description (.toml)")->required();
  render_cmd->add_option("-b,--bake", render.bake, "bake file (default: from the scene)");
  render_cmd->add_option("-o,--output", render.output, "PNG image (default: from the scene)");
  render_cmd->add_flag("--force", render.force, kForceHelp);
  render_cmd->add_flag("--ground-truth", render.ground_truth,
                       "render the Monte Carlo ground truth instead of the bake");
  render_cmd->add_option("-r,--renderer", render.renderer,
                         "renderer plug-in instead of the scene's (e.g. opengl)");
  render_cmd->add_option("--renderer-param", render.renderer_parameters,
                         "key=value parameter of that renderer (repeatable)");
  render_cmd->add_flag("--compare", render.compare,
                       "also compute the ground truth and print per-vertex RMS error");
  render_cmd
      ->add_option("--exposure", render.exposure,
                   "exposure scale of the PNG (default: the scene's)")
      ->check(CLI::Validator(
          [](const std::string& text) -> std::string {
            // CLI11's PositiveNumber lets NaN through (every comparison with it is false).
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (end == text.c_str() || *end != '\0' || !std::isfinite(value) || !(value > 0))
              return "exposure \"" + prt::elide(text) + "\" is not a finite positive number";
            return "";
          },
          "POSITIVE"));

  prt::cli::CompressArgs compress;
  auto* compress_cmd =
      app.add_subcommand("compress", "re-compress the transfer of a bake file with a compressor");
  compress_cmd->add_option("bake", compress.bake, "bake file (.h5)")->required();
  compress_cmd->add_option("-c,--compressor", compress.compressor, "compressor plug-in")
      ->required();
  compress_cmd->add_option("-p,--param", compress.parameters,
                           "compressor parameter key=value (repeatable)");
  compress_cmd->add_option("-o,--output", compress.output, "output bake file (default: in place)");
  compress_cmd->add_flag("--json", compress.json, "print the metrics as JSON");
  compress_cmd->add_flag("--force", compress.force, kForceHelp);
  compress_cmd
      ->add_option("--memory", compress.memory,
                   "memory budget, e.g. 8G (default: 3/4 of RAM); a larger transfer is read "
                   "into a file beside the output and compressed in passes")
      ->transform(CLI::AsSizeValue(false))
      ->check(CLI::Range(std::uint64_t(1) << 20, std::uint64_t(1) << 50));

  prt::cli::AnalyzeArgs analyze;
  auto* analyze_cmd = app.add_subcommand("analyze", "numerical analyses");
  auto* hemisphere_cmd = analyze_cmd->add_subcommand(
      "hemisphere", "conditioning and errors of hemispherical SH projections (Sloan 2003 §9)");
  analyze_cmd->require_subcommand(1);
  hemisphere_cmd->add_option("--order", analyze.order, "SH order N (N^2 functions)")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  hemisphere_cmd
      ->add_option("--cutoff", analyze.cutoff,
                   "least squares: discard singular values below this x the largest")
      ->capture_default_str();
  hemisphere_cmd->add_option("--odd", analyze.odd_orders, "orders of the odd-reflection bases")
      ->capture_default_str();
  hemisphere_cmd->add_option("--even", analyze.even_orders, "orders of the even-reflection bases")
      ->capture_default_str();
  hemisphere_cmd->add_flag("--json", analyze.json, "print JSON");

  prt::cli::BenchArgs bench;
  auto* bench_cmd = app.add_subcommand(
      "bench", "sweep parameters; measure bake/encode/relight time, size and error");
  bench_cmd->add_option("scene", bench.scene, "scene description (.toml)")->required();
  bench_cmd->add_option("--sweep", bench.sweeps, "section.key=v1,v2,... (repeatable)");
  bench_cmd->add_option("--out", bench.out, "output folder (default: bench_<scene>)");
  bench_cmd->add_option("--lights", bench.lights, "lights: the scene's and rotated copies")
      ->check(CLI::Range(1, 64));
  bench_cmd->add_flag("--gpu", bench.gpu, "also time the OpenGL renderer (needs a display)");
  bench_cmd->add_flag("--no-report", bench.no_report, "skip the plots and the Markdown report");
  bench_cmd->add_flag("--force", bench.force, kForceHelp);

  prt::cli::StabilityArgs stability;
  auto* stability_cmd =
      app.add_subcommand("stability", "report where the numerics break (SH, rotation, ...)");
  stability_cmd->add_option("--orders", stability.orders, "SH orders (bands) to measure")
      ->delimiter(',');
  stability_cmd->add_option("--max-rotation-order", stability.max_rotation_order,
                            "largest order whose rotation is measured");
  stability_cmd
      ->add_option("--bands", stability.bands,
                   "single bands l measured alone to high degree (rotation, evaluation)")
      ->delimiter(',');
  stability_cmd->add_option("--hemisphere-order", stability.hemisphere_order,
                            "largest order of the hemispherical Gram matrix");
  stability_cmd->add_option("--json", stability.json, "write the figures as JSON");
  stability_cmd->add_option("--figure-data", stability.figure_data,
                            "write the sun-ringing curves as CSV (for scripts/stability_plot.py)");
  stability_cmd->add_flag("--force", stability.force, kForceHelp);

  std::vector<std::string> diff_images;
  auto* diff_cmd = app.add_subcommand(
      "image-diff", "mean absolute difference of two PNG images (0..255 per channel)");
  diff_cmd->add_option("images", diff_images, "two PNG files")->required()->expected(2);

  prt::cli::CompareArgs compare;
  auto* compare_cmd = app.add_subcommand(
      "compare-bases", "trace once, then compare bases by transport and shading error");
  compare_cmd->add_option("scene", compare.scene, "scene description (.toml)")->required();
  compare_cmd
      ->add_option("--bases", compare.bases,
                   "comma-separated name[:key=value...], e.g. sh:order=10,haar:k=96,eigen:d=48")
      ->required();
  compare_cmd->add_option("--csv", compare.csv, "write the table as CSV");
  compare_cmd->add_option("--json", compare.json, "write the table as JSON");
  compare_cmd->add_flag("--force", compare.force, kForceHelp);

  std::string info_file;
  auto* info_cmd = app.add_subcommand("info", "print a bake file's contents");
  info_cmd->add_option("bake", info_file, "bake file (.h5)")->required();

  auto* plugins_cmd =
      app.add_subcommand("plugins", "list plug-ins: kind, name, version, parameters");

  prt::cli::SubdivideArgs subdivide;
  auto* subdivide_cmd = app.add_subcommand(
      "subdivide", "make a large test mesh: Loop or midpoint subdivision to a vertex count");
  subdivide_cmd->add_option("mesh", subdivide.input, "input mesh (.off, .ply, .obj, .stl)")
      ->required();
  subdivide_cmd
      ->add_option("-o,--output", subdivide.output, "output mesh (.ply binary, .off, .obj)")
      ->required();
  subdivide_cmd->add_option("-n,--vertices", subdivide.vertices, "vertex count of the result")
      ->required();
  subdivide_cmd->add_option("--scheme", subdivide.scheme, "loop (smooth) or midpoint (flat)")
      ->capture_default_str();
  subdivide_cmd->add_flag("--force", subdivide.force, kForceHelp);

  prt::cli::DemoArgs demo;
  auto* demo_cmd = app.add_subcommand("demo", "bake and render the default scene");
  demo_cmd->add_option("scene", demo.scene, "scene (default: scenes/bunny.toml)");

  CLI11_PARSE(app, argc, argv);
  prt::Progress::set_enabled(!quiet);
  try {
    prt::cli::Context context{prt::PluginRegistry(prt::PluginRegistry::default_directories()),
                              quiet};
    for (const auto& problem : context.registry.problems())
      std::cerr << "prt: warning: " << problem.message << "\n";
    if (*bake_cmd) return prt::cli::bake(context, bake);
    if (*render_cmd) return prt::cli::render(context, render);
    if (*compress_cmd) return prt::cli::compress(context, compress);
    if (*info_cmd) return prt::cli::info(info_file);
    if (*hemisphere_cmd) return prt::cli::analyze_hemisphere(analyze);
    if (*compare_cmd) return prt::cli::compare_bases(context, compare);
    if (*bench_cmd) return prt::cli::bench(context, bench);
    if (*stability_cmd) return prt::cli::stability(context, stability);
    if (*diff_cmd) return prt::cli::image_diff(diff_images[0], diff_images[1]);
    if (*plugins_cmd) return prt::cli::plugins(context);
    if (*demo_cmd) return prt::cli::demo(context, demo);
    if (*subdivide_cmd) return prt::cli::subdivide(subdivide);
  } catch (...) {
    std::cerr << "prt: " << prt::current_error_line() << "\n";
    return 1;
  }
  return 0;
}
