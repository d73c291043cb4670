// prt: bake, render and inspect precomputed radiance transfer.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <vector>

#include "commands.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"

namespace {

const char* kForceHelp = "replace an existing output file of another kind (never an input)";

// A subcommand and what runs it; each keeps its arguments alive in the runner.
struct Command {
  CLI::App* cli;
  std::function<int(prt::cli::Context&)> run;
};

// prt bake
Command bake_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::BakeArgs>();
  auto* command = prt::cli::add_bake_command(
      app, *args,
      "memory budget, e.g. 8G or 512M (default: 3/4 of RAM); a larger transfer is kept on disk "
      "and compressed in passes",
      "compression keeps its state in the checkpoint at most this often");
  return {command, [args](prt::cli::Context& context) { return prt::cli::bake(context, *args); }};
}

// The reference options of render --compare, bench and compare-bases.
void add_reference_options(CLI::App* command, prt::cli::ReferenceArgs& args) {
  command
      ->add_option("--samples", args.samples,
                   "Monte Carlo samples per vertex of the ground truth (default: the scene's "
                   "[ground_truth] samples); the noise floor falls at least as 1/sqrt(samples)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1048576)));
  command->add_option("--cache", args.cache,
                      "folder of reused ground truths (default: $PRT_CACHE_DIR, else "
                      "$XDG_CACHE_HOME/prt, else ~/.cache/prt)");
  command->add_flag("--no-cache", args.no_cache, "trace the ground truth anew and keep nothing");
}

// prt render
Command render_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::RenderArgs>();
  auto* command = app.add_subcommand("render", "relight a bake and write an image");
  command->add_option("scene", args->scene, "scene description (.toml)")->required();
  command->add_option("-b,--bake", args->bake, "bake file (default: from the scene)");
  command->add_option("-o,--output", args->output,
                      "image: .png (8-bit sRGB) or .exr (linear float) (default: from the scene)");
  command->add_flag("--force", args->force, kForceHelp);
  command->add_flag("--ground-truth", args->ground_truth,
                    "render the Monte Carlo ground truth instead of the bake");
  command->add_option("-r,--renderer", args->renderer,
                      "renderer plug-in instead of the scene's (e.g. opengl)");
  command->add_option("--renderer-param", args->renderer_parameters,
                      "key=value parameter of that renderer (repeatable)");
  command->add_flag("--compare", args->compare,
                    "also compute the ground truth (cached): per-vertex RMS with its noise "
                    "floor, PSNR and SSIM, the error budget, and NAME.error.png, "
                    "NAME.error.exr and NAME.truth.EXT beside the image");
  command->add_flag("--no-budget", args->no_budget,
                    "with --compare: skip the error budget, which traces a second ground truth "
                    "under the band-limited light");
  add_reference_options(command, args->reference);
  command
      ->add_option("--exposure", args->exposure, "exposure scale of the PNG (default: the scene's)")
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
  return {command, [args](prt::cli::Context& context) { return prt::cli::render(context, *args); }};
}

// prt compress
Command compress_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::CompressArgs>();
  auto* command =
      app.add_subcommand("compress", "re-compress the transfer of a bake file with a compressor");
  command->add_option("bake", args->bake, "bake file (.h5)")->required();
  command->add_option("-c,--compressor", args->compressor, "compressor plug-in (or --sweep)");
  command->add_option("--sweep", args->sweeps,
                      "rank several encodings instead of writing one: 'vq clusters=256|pca "
                      "components=8|cpca clusters=64 components=4' (repeatable); nothing is "
                      "written");
  command
      ->add_option("--budget", args->budgets,
                   "with --sweep: the most accurate encoding within this many bytes, e.g. 2M "
                   "(repeatable)")
      ->transform(CLI::AsSizeValue(false));
  command->add_option("-p,--param", args->parameters,
                      "compressor parameter key=value (repeatable)");
  command->add_option("-o,--output", args->output, "output bake file (default: in place)");
  command->add_flag("--json", args->json, "print the metrics as JSON");
  command->add_flag("--force", args->force, kForceHelp);
  command
      ->add_option("--memory", args->memory,
                   "memory budget, e.g. 8G (default: 3/4 of RAM); a larger transfer is read "
                   "into a file beside the output and compressed in passes")
      ->transform(CLI::AsSizeValue(false))
      ->check(CLI::Range(std::uint64_t(1) << 20, std::uint64_t(1) << 50));
  return {command, [args](prt::cli::Context& context) {
            if (!args->sweeps.empty()) return prt::cli::compress_sweep(context, *args);
            if (args->compressor.empty())
              throw prt::Error(
                  "prt compress: name a compressor (-c NAME) or sweep several "
                  "(--sweep 'NAME k=v|NAME k=v')");
            return prt::cli::compress(context, *args);
          }};
}

// prt bench
Command bench_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::BenchArgs>();
  auto* command = app.add_subcommand(
      "bench", "sweep parameters; measure bake/encode/relight time, size and error");
  command->add_option("scene", args->scene, "scene description (.toml)")->required();
  command->add_option("--sweep", args->sweeps, "section.key=v1,v2,... (repeatable)");
  command->add_option("--out", args->out, "output folder (default: bench_<scene>)");
  command->add_option("--lights", args->lights, "lights: the scene's and rotated copies")
      ->check(CLI::Range(1, 64));
  command->add_flag("--gpu", args->gpu, "also time the OpenGL renderer (needs a display)");
  command->add_flag("--no-report", args->no_report, "skip the plots and the Markdown report");
  command
      ->add_option("--budget", args->budget,
                   "bytes of the compressed form the report's recommendation must fit, e.g. 4M")
      ->transform(CLI::AsSizeValue(false));
  add_reference_options(command, args->reference);
  command->add_flag("--force", args->force, kForceHelp);
  return {command, [args](prt::cli::Context& context) { return prt::cli::bench(context, *args); }};
}

// prt stability
Command stability_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::StabilityArgs>();
  auto* command =
      app.add_subcommand("stability", "report where the numerics break (SH, rotation, ...)");
  command->add_option("--orders", args->orders, "SH orders (bands) to measure")->delimiter(',');
  command->add_option("--max-rotation-order", args->max_rotation_order,
                      "largest order whose rotation is measured");
  command
      ->add_option("--bands", args->bands,
                   "single bands l measured alone to high degree (rotation, evaluation)")
      ->delimiter(',');
  command->add_option("--hemisphere-order", args->hemisphere_order,
                      "largest order of the hemispherical Gram matrix");
  command->add_option("--json", args->json, "write the figures as JSON");
  command->add_option("--figure-data", args->figure_data,
                      "write the sun-ringing curves as CSV (for scripts/stability_plot.py)");
  command->add_flag("--force", args->force, kForceHelp);
  return {command,
          [args](prt::cli::Context& context) { return prt::cli::stability(context, *args); }};
}

// prt compare-bases
Command compare_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::CompareArgs>();
  auto* command = app.add_subcommand(
      "compare-bases", "trace once, then compare bases by transport and shading error");
  command->add_option("scene", args->scene, "scene description (.toml)")->required();
  command
      ->add_option("--bases", args->bases,
                   "comma-separated name[:key=value...], e.g. sh:order=10,haar:k=96,eigen:d=48")
      ->required();
  command->add_option("--csv", args->csv, "write the table as CSV");
  command->add_option("--json", args->json, "write the table as JSON");
  command->add_flag("--force", args->force, kForceHelp);
  add_reference_options(command, args->reference);
  return {command,
          [args](prt::cli::Context& context) { return prt::cli::compare_bases(context, *args); }};
}

// prt texels
Command texels_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::TexelsArgs>();
  auto* command = app.add_subcommand(
      "texels",
      "bake a texel scene at its texels and at its mesh's vertices and measure both against "
      "the ground truth at points over the surface");
  command->add_option("scene", args->scene, "scene description with [receivers] kind = \"texels\"")
      ->required();
  command
      ->add_option("--resolution", args->resolutions,
                   "atlas resolution to bake and measure (repeatable; default: the scene's "
                   "[receivers] resolution)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(8192)));
  command->add_option("--points", args->points, "surface points the error is measured at")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(10000000)));
  command->add_option("--out", args->out,
                      "folder for images at the last --resolution: per texel, per vertex, and "
                      "the truth (at the texels of a 4x finer atlas)");
  command
      ->add_option("--samples", args->reference.samples,
                   "Monte Carlo samples per point of the ground truth (default: the scene's "
                   "[ground_truth] samples)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1048576)));
  return {command, [args](prt::cli::Context& context) { return prt::cli::texels(context, *args); }};
}

// prt probes
Command probes_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::ProbesArgs>();
  auto* command = app.add_subcommand(
      "probes",
      "shade a probe scene's moving object from its probes, with and without the leak "
      "control, against the ground truth");
  command->add_option("scene", args->scene, "scene description with [receivers] kind = \"probes\"")
      ->required();
  command->add_option("-b,--bake", args->bake, "bake file (default: from the scene)");
  command->add_option("--at", args->at,
                      "x,y,z: where the moving object's bottom centre goes (repeatable; default: "
                      "the scene's [moving] position)");
  command->add_option("--out", args->out,
                      "folder for images of each position: leak control, trilinear, truth");
  command  // the truths depend on the object's place, so none is cached
      ->add_option("--samples", args->reference.samples,
                   "Monte Carlo samples per vertex of the ground truth (default: the scene's "
                   "[ground_truth] samples)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1048576)));
  return {command, [args](prt::cli::Context& context) { return prt::cli::probes(context, *args); }};
}

// prt subdivide
Command subdivide_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::SubdivideArgs>();
  auto* command = app.add_subcommand(
      "subdivide", "make a large test mesh: Loop or midpoint subdivision to a vertex count");
  command->add_option("mesh", args->input, "input mesh (.off, .ply, .obj, .stl)")->required();
  command->add_option("-o,--output", args->output, "output mesh (.ply binary, .off, .obj)")
      ->required();
  command->add_option("-n,--vertices", args->vertices, "vertex count of the result")->required();
  command->add_option("--scheme", args->scheme, "loop (smooth) or midpoint (flat)")
      ->capture_default_str();
  command->add_flag("--force", args->force, kForceHelp);
  return {command, [args](prt::cli::Context& context) {
            return ((void)context, prt::cli::subdivide(*args));
          }};
}

// prt demo
Command demo_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::DemoArgs>();
  auto* command = app.add_subcommand("demo", "bake and render the default scene");
  command->add_option("scene", args->scene, "scene (default: scenes/bunny.toml)");
  return {command, [args](prt::cli::Context& context) { return prt::cli::demo(context, *args); }};
}

// prt analyze hemisphere
Command analyze_command(CLI::App& app) {
  auto args = std::make_shared<prt::cli::AnalyzeArgs>();
  auto* analyze = app.add_subcommand("analyze", "numerical analyses");
  auto* command = analyze->add_subcommand(
      "hemisphere", "conditioning and errors of hemispherical SH projections (Sloan 2003 §9)");
  analyze->require_subcommand(1);
  command->add_option("--order", args->order, "SH order N (N^2 functions)")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  command
      ->add_option("--cutoff", args->cutoff,
                   "least squares: discard singular values below this x the largest")
      ->capture_default_str();
  command->add_option("--odd", args->odd_orders, "orders of the odd-reflection bases")
      ->capture_default_str();
  command->add_option("--even", args->even_orders, "orders of the even-reflection bases")
      ->capture_default_str();
  command->add_flag("--json", args->json, "print JSON");
  return {command, [args](prt::cli::Context&) { return prt::cli::analyze_hemisphere(*args); }};
}

// prt image-diff
Command image_diff_command(CLI::App& app) {
  auto images = std::make_shared<std::vector<std::string>>();
  auto* command = app.add_subcommand(
      "image-diff",
      "mean absolute difference, PSNR and SSIM of two PNG images (0..255 per channel)");
  command->add_option("images", *images, "two PNG files")->required()->expected(2);
  return {command, [images](prt::cli::Context&) {
            return prt::cli::image_diff((*images)[0], (*images)[1]);
          }};
}

// prt info
Command info_command(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto* command = app.add_subcommand("info", "print a bake file's contents");
  command->add_option("bake", *file, "bake file (.h5)")->required();
  return {command, [file](prt::cli::Context& context) { return prt::cli::info(context, *file); }};
}

// prt plugins
Command plugins_command(CLI::App& app) {
  auto* command = app.add_subcommand("plugins", "list plug-ins: kind, name, version, parameters");
  return {command, [](prt::cli::Context& context) { return prt::cli::plugins(context); }};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"prt: precomputed radiance transfer with plug-in bases, compressors and renderers"};
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "no progress bars");
  const std::vector<Command> commands{
      bake_command(app),   render_command(app),    compress_command(app),   analyze_command(app),
      bench_command(app),  stability_command(app), image_diff_command(app), compare_command(app),
      info_command(app),   plugins_command(app),   subdivide_command(app),  demo_command(app),
      probes_command(app), texels_command(app)};
  CLI11_PARSE(app, argc, argv);
  prt::Progress::set_enabled(!quiet);
  try {
    prt::cli::Context context{prt::PluginRegistry(prt::PluginRegistry::default_directories()),
                              quiet};
    for (const auto& problem : context.registry.problems())
      std::cerr << "prt: warning: " << problem.message << "\n";
    for (const Command& command : commands)
      if (*command.cli) return command.run(context);
  } catch (...) {
    std::cerr << "prt: " << prt::current_error_line() << "\n";
    return 1;
  }
  return 0;
}
