#include "commands.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <tuple>

#include "image_outputs.hpp"
#include "prt/bake_file.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/image_metrics.hpp"
#include "prt/memory.hpp"
#include "prt/mesh_compose.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/row_file.hpp"
#include "reference_options.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace prt::cli {
namespace fs = std::filesystem;

namespace {

void print_times(const StageTimes& times) {
  std::cout << "timings:\n" << times.table();
}

std::string describe_shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

}  // namespace

int bake(Context& context, const BakeArgs& args) {
  Stopwatch clock;
  const SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  StageTimes times;
  times.add("parse + validate scene", clock.seconds());
  clock = Stopwatch();
  const BakePlan plan = plan_bake(scene, context.registry);
  times.add("load plug-ins", clock.seconds());
  // A killed bake rerun with the same command resumes from its checkpoint.
  const BakeTarget target = bake_target(scene, args, "prt bake");
  const RunOptions options = bake_run_options(args, context.quiet);
  BakeData data = bake_to_file(scene, plan, target, options, times);
  const Eigen::Index columns =
      data.streamed_transfer.rows > 0 ? data.streamed_transfer.cols : data.transfer.dimension();
  std::cout << "baked " << data.receiver_count() << " "
            << (data.receivers.at_vertices() ? "vertices" : data.receivers.kind) << " x " << columns
            << " coefficients (" << data.basis.name << ", " << data.transport << ") -> "
            << target.file.path.string() << "\n"
            << "rays cast: " << static_cast<std::uint64_t>(data.metrics["rays_cast"]) << "\n";
  std::printf("peak memory: %.3f GB (resident; budget %.3f GB)\n", peak_resident_bytes() / 1e9,
              options.budget() / 1e9);
  print_times(times);
  return 0;
}

void parse_parameter(const std::string& text, std::size_t index, Params& params);

// What the comparisons of one render share, made once.
struct Comparison {
  const SceneSpec& scene;
  const BakeData& data;
  const Relighting& relighting;
  const Environment& environment;
  const Eigen::MatrixX3d& light;
  const Camera& camera;
};

void print_error_budget(const Comparison& with, const Reference& truth,
                        const Eigen::MatrixX3f& compressed, Context& context,
                        const ReferenceCache* cache, StageTimes& times);

// The scene's renderer, or the one --renderer names with its --renderer-param values.
void override_renderer(Context& context, const RenderArgs& args, SceneSpec& scene) {
  if (args.renderer.empty()) return;
  PluginChoice choice{args.renderer, SourceLocation{"--renderer"}, Params({"--renderer"})};
  for (std::size_t i = 0; i < args.renderer_parameters.size(); ++i)
    parse_parameter(args.renderer_parameters[i], i, choice.params);
  choice.params.validate(
      context.registry.find(PluginKind::renderer, choice.name, choice.where).schema());
  scene.renderer = std::move(choice);
}

// prt render --compare: the render against the Monte Carlo ground truth
// (with its noise floor, reused from the cache when it holds it), the image
// metrics and error images, then what each part of the approximation costs.
void compare_with_truth(Context& context, const RenderArgs& args, const SceneSpec& scene,
                        const BakeData& data, const Rendered& result, StageTimes& times,
                        const fs::path& output) {
  const auto cache = reference_cache(args.reference);
  const ReferenceCache* kept = cache.get();
  const Environment environment = scene.load_environment();
  const Camera camera = scene.make_camera(data.mesh);
  Stopwatch clock;
  const Reference truth =
      reference_radiance(scene, data.mesh, environment, camera, {context.quiet}, kept);
  times.add(truth.cached.empty() ? "ground truth (Monte Carlo)" : "ground truth (cached)",
            clock.seconds());
  clock = Stopwatch();
  const Image truth_image =
      render_reference(scene, data.mesh, context.registry, truth.radiance, environment);
  times.add("rasterise the ground truth", clock.seconds());
  const double floor = truth.noise_floor();
  std::printf("%s\n", reference_summary(truth).c_str());
  const ErrorStats e = vertex_error(result.vertex_radiance, truth.radiance);
  std::printf(
      "error against ground truth (%d samples/vertex): RMS per vertex %.6g (relative %.4f), %s,"
      " 99th percentile %.6g, max %.6g\n",
      truth.samples, e.rms, e.relative_rms, noise_note(e.rms, floor).c_str(), e.p99, e.max);
  const float exposure = static_cast<float>(keys::camera::exposure(scene.camera));
  const DarkPixels dark = count_dark_pixels(result.image, truth_image, exposure);
  std::printf(
      "pixels darker than half the ground truth (of %lld with ground-truth luminance > 40 of "
      "255 at the scene's exposure): %lld\n",
      dark.lit, dark.dark);
  write_comparison(result.image, truth_image, exposure, comparison_files(output));
  // One relighting and light vector for every comparison below.
  const Relighting relighting(scene, data, context.registry);
  const Eigen::MatrixX3d light = relighting.light(environment);
  if (!scene.point_lights.empty()) {  // the nearest-direction rule against its reference
    Relighting brute(scene, data, context.registry);
    brute.use_brute_force(256);
    const Relit reprojected = brute.relight(data.compressed, light, camera);
    const ErrorStats b = vertex_error(reprojected.vertex_radiance, truth.radiance);
    std::printf(
        "error of brute-force re-projection of the point lights (%s) against the same "
        "ground truth: RMS per vertex %.6g (relative %.4f), %s\n",
        brute.point_light_rule().c_str(), b.rms, b.relative_rms, noise_note(b.rms, floor).c_str());
  }
  if (data.direct.coefficients.size()) {  // what the bounces bring
    const Relit direct = relighting.relight(exact_form(data.direct), light, camera);
    const ErrorStats d = vertex_error(direct.vertex_radiance, truth.radiance);
    std::printf(
        "error of the same transfer without its %d bounces (exact, no compression) against "
        "the same ground truth: RMS per vertex %.6g (relative %.4f), %s\n",
        data.bounces, d.rms, d.relative_rms, noise_note(d.rms, floor).c_str());
  }
  if (!args.no_budget)
    print_error_budget({scene, data, relighting, environment, light, camera}, truth,
                       result.vertex_radiance, context, kept, times);
}

int render(Context& context, const RenderArgs& args) {
  Stopwatch clock;
  SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  override_renderer(context, args, scene);
  StageTimes times;
  times.add("parse + validate scene", clock.seconds());
  // The ground truth's default is the name --compare gives it (scene.truth.png),
  // so that it never replaces the scene's render.
  const fs::path output = !args.output.empty() ? fs::path(args.output)
                          : args.ground_truth  ? comparison_files(scene.image_path()).truth
                                               : scene.image_path();
  const fs::path bake_file = args.bake.empty() ? scene.bake_path() : fs::path(args.bake);
  std::vector<fs::path> inputs = scene.input_files();
  inputs.push_back(bake_file);
  const FileKind image_kind = output.extension() == ".exr" ? FileKind::exr : FileKind::png;
  check_output({output, image_kind, "image", args.output.empty()}, inputs, args.force);
  image_format(output);  // an unknown extension is refused before any work
  if (args.compare)
    check_comparison_files(comparison_files(output), inputs, args.force, args.output.empty());
  apply_samples(args.reference, scene);

  Rendered result;
  if (args.ground_truth) {
    Mesh mesh = scene.load_mesh();
    if (scene.has_moving()) append(mesh, scene.load_moving());  // a probe scene's object
    result = render_ground_truth(scene, mesh, context.registry, {context.quiet}, times, nullptr,
                                 reference_cache(args.reference).get());
  } else {
    clock = Stopwatch();
    const BakeData data = read_bake(bake_file);
    check_bake_records(bake_file.string(), data, context.registry);
    times.add("read bake file", clock.seconds());
    if (args.compare && data.receivers.probes())
      throw Error(bake_file.string() +
                  ": --compare measures transfer at vertices; for probes, "
                  "`prt probes " +
                  args.scene +
                  "` measures the moving object "
                  "against its ground truth");
    if (args.compare && data.receivers.texels())
      throw Error(bake_file.string() +
                  ": --compare measures transfer at vertices; for texels, `prt texels " +
                  args.scene +
                  "` measures them and the mesh's vertices against the ground truth at points over "
                  "the surface");
    result = render(scene, data, context.registry, times, {context.quiet});
    if (args.compare) compare_with_truth(context, args, scene, data, result, times, output);
  }
  clock = Stopwatch();
  const float exposure =
      args.exposure > 0 ? args.exposure : static_cast<float>(keys::camera::exposure(scene.camera));
  write_image(result.image, output, exposure);
  times.add(image_kind == FileKind::exr ? "write EXR" : "write PNG", clock.seconds());
  std::cout << "rendered " << result.image.width << " x " << result.image.height << " -> "
            << output.string() << "\n";
  for (const auto& [name, value] : result.statistics)
    std::cout << "renderer " << name << ": " << value << "\n";
  print_times(times);
  return 0;
}

// Where the error comes from: the light basis's truncation of the light
// (ground truth under the band-limited light against the full one), the
// transfer's projection (exact PRT against the band-limited truth) and the
// compression (compressed against exact PRT). RMS per vertex, as above.
void print_error_budget(const Comparison& with, const Reference& truth,
                        const Eigen::MatrixX3f& compressed, Context& context,
                        const ReferenceCache* cache, StageTimes& times) {
  const auto& [scene, data, relighting, environment, light, camera] = with;
  Stopwatch clock;
  const Reference limited_truth = band_limited_truth(scene, data.mesh, relighting, environment,
                                                     light, camera, {context.quiet}, cache);
  times.add("ground truth under the band-limited light", clock.seconds());
  const Eigen::MatrixX3f exact =
      relighting.relight(exact_form(data.transfer), light, camera).vertex_radiance;
  const ErrorBudget budget =
      error_budget(truth.radiance, limited_truth.radiance, exact, compressed);
  // A difference of two references carries both their noises.
  const double floor = truth.noise_floor(), limited_floor = limited_truth.noise_floor();
  const double both = std::hypot(floor, limited_floor);
  std::printf("error budget (per-vertex RMS; each term's noise floor beside it):\n");
  for (const auto& [what, error, noise] :
       {std::tuple{"light truncation (band-limited vs full ground truth)", budget.truncation, both},
        {"transfer projection (exact PRT vs band-limited ground truth)", budget.projection,
         limited_floor},
        {"compression (compressed vs exact PRT)", budget.compression, 0.0},
        {"total (compressed PRT vs full ground truth)", budget.total, floor}})
    std::printf("  %-62s %.6g  (%s)\n", what, error,
                noise > 0 ? noise_note(error, noise).c_str() : "exact: no Monte Carlo noise");
}

// "key=value" from the command line, typed as TOML would type the value.
void parse_parameter(const std::string& text, std::size_t index, Params& params) {
  parse_assignment(text, SourceLocation{"command line parameter " + std::to_string(index + 1)},
                   params);
}

int compress(Context& context, const CompressArgs& args) {
  const fs::path output = args.output.empty() ? fs::path(args.bake) : fs::path(args.output);
  if (!args.output.empty())  // without -o the bake is re-compressed in place, atomically
    check_output({output, FileKind::bake, "output bake file"}, {args.bake}, args.force);
  Stopwatch clock;
  RunOptions budget;
  budget.memory_budget = double(args.memory);
  ReadOptions reading{budget.budget(), output.has_parent_path() ? output.parent_path() : "."};
  BakeData data = read_bake(args.bake, reading);
  check_bake_records(args.bake, data, context.registry);
  StageTimes times;
  times.add("read bake file", clock.seconds());
  if (data.transfer.on_disk() && !args.json)
    std::cout << "the transfer ("
              << describe_shape(data.transfer.vertices(), data.transfer.dimension())
              << ") and mesh exceed the memory budget: its rows are kept in "
              << reading.rows_folder.string() << " and compressed in passes over them\n";
  Params params(SourceLocation{"command line"});
  for (std::size_t i = 0; i < args.parameters.size(); ++i)
    parse_parameter(args.parameters[i], i, params);
  auto compressor = context.registry.create<Compressor>(args.compressor, params);
  refuse_budget_beyond_signal(params, data.transfer.dimension(), args.compressor);
  const RenderedMetric metric = rendered_metric(data, context.registry);
  clock = Stopwatch();
  std::optional<TransferSignal> loaded;
  const Distribution whole = Distribution::whole_signal(data.transfer.vertices());
  data.compressed = encode_in_metric(
      *compressor, readable_signal(*compressor, args.compressor, data.transfer, loaded),
      &data.row_mesh(), whole, metric);
  loaded.reset();
  const double seconds = clock.seconds();
  times.add("compress (" + args.compressor + ")", seconds);
  const CompressionReport report =
      measure(data.transfer, data.compressed, &data.row_mesh(), seconds, whole, &metric);
  record(report, data.metrics);
  const auto& info = context.registry.find(PluginKind::compressor, args.compressor);
  data.compressor = {args.compressor, info.info.version, params.describe()};
  clock = Stopwatch();
  write_bake(output, data);
  times.add("write bake file", clock.seconds());
  if (args.json) {
    std::cout << report.json() << "\n";
    return 0;
  }
  std::cout << args.compressor << " -> " << output.string() << "\n" << report.text();
  std::printf("peak memory: %.3f GB (resident; budget %.3f GB)\n", peak_resident_bytes() / 1e9,
              budget.budget() / 1e9);
  print_times(times);
  return 0;
}

int info(Context& context, const std::string& file) {
  const BakeData data = read_bake(file);
  const std::vector<std::string> unchecked = check_bake_records(file, data, context.registry);
  const CompressedTransfer& c = data.compressed;
  const ProbeGrid& grid = data.receivers.grid;
  std::cout << "bake file:    " << file << " (format version " << data.format_version() << ")\n"
            << "scene:        " << data.scene_file << "\n"
            << "mesh:         " << data.mesh.vertex_count() << " vertices, "
            << data.mesh.triangle_count() << " triangles\n"
            << "transport:    " << data.transport << "\n"
            << (data.receivers.probes()
                    ? "receivers:    probes, " + std::to_string(grid.counts[0]) + " x " +
                          std::to_string(grid.counts[1]) + " x " + std::to_string(grid.counts[2]) +
                          " every " + std::to_string(grid.spacing) + " from (" +
                          std::to_string(grid.origin.x()) + ", " + std::to_string(grid.origin.y()) +
                          ", " + std::to_string(grid.origin.z()) + ")\n"
                : data.receivers.texels()
                    ? "receivers:    texels, " +
                          std::to_string(data.receivers.atlas.texels.size()) + " of a " +
                          std::to_string(data.receivers.atlas.width) + " x " +
                          std::to_string(data.receivers.atlas.height) + " atlas\n"
                    : std::string("receivers:    the mesh's vertices\n"))
            << "basis:        " << one_line(data.basis) << "\n"
            << (data.transfer.glossy()    ? "exit basis:   " + one_line(data.exit) + "\n"
                : data.receivers.probes() ? "incident:     " + one_line(data.exit) + "\n"
                                          : "")
            << "transfer:     " << data.transfer.kind << ", "
            << describe_shape(data.transfer.vertices(), data.transfer.dimension())
            << (data.transfer.channel_groups > 1
                    ? ", " + std::to_string(data.transfer.channel_groups) +
                          " channel transfers (R, G, B read " +
                          std::to_string(data.transfer.group_of_channel[0] + 1) + ", " +
                          std::to_string(data.transfer.group_of_channel[1] + 1) + ", " +
                          std::to_string(data.transfer.group_of_channel[2] + 1) + ")"
                    : std::string())
            << (data.bounces > 0 ? ", " + std::to_string(data.bounces) + " bounces" : "") << "\n"
            << "material:     " << data.material << "\n"
            << "compressor:   " << one_line(data.compressor) << ": " << c.clusters()
            << " cluster(s), " << c.components << " component(s), " << c.stored_floats()
            << " floats stored\n"
            << "albedo:       " << data.albedo.transpose() << "\n";
  std::cout << "records:      "
            << (unchecked.empty() ? "checked against the installed plug-ins" : "not checked:");
  for (std::size_t i = 0; i < unchecked.size(); ++i) std::cout << (i ? ", " : " ") << unchecked[i];
  std::cout << (unchecked.empty() ? "\n" : " (plug-in not installed)\n") << "metrics:\n";
  for (const auto& [name, value] : data.metrics)
    std::cout << "  " << name << " = " << value << "\n";
  return 0;
}

int plugins(Context& context) {
  for (const auto& p : context.registry.plugins()) {
    std::cout << to_string(p.kind()) << " " << p.name() << " " << p.info.version << "  ("
              << p.file.string() << ")\n    " << p.info.description << "\n";
    for (const auto& spec : p.schema().specs) {
      std::cout << "    " << spec.name << " : " << to_string(spec.type);
      if (spec.default_value[0]) std::cout << " = " << spec.default_value;
      if (spec.type == ParamType::integer || spec.type == ParamType::real)
        std::cout << "  in [" << spec.min << ", " << spec.max << "]";
      if (spec.choices[0]) std::cout << "  one of " << spec.choices;
      std::cout << "  -- " << spec.help << "\n";
    }
  }
  return 0;
}

int demo(Context& context, const DemoArgs& args) {
  const std::string scene =
      args.scene.empty() ? std::string(PRT_SOURCE_DIR) + "/scenes/bunny.toml" : args.scene;
  if (int code = bake(context, {scene, ""})) return code;
  RenderArgs render_args;
  render_args.scene = scene;
  return render(context, render_args);
}

int image_diff(const std::string& a_file, const std::string& b_file) {
  const Image8 a = read_png(a_file), b = read_png(b_file);
  if (a.width != b.width || a.height != b.height)
    throw Error(b_file + ": " + std::to_string(b.width) + "x" + std::to_string(b.height) +
                ", but " + a_file + " is " + std::to_string(a.width) + "x" +
                std::to_string(a.height));
  double sum = 0;
  std::size_t differing = 0;
  for (std::size_t p = 0; p < a.rgb.size(); p += 3) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(a.rgb[p + c]) - int(b.rgb[p + c]));
      sum += d;
      worst = std::max(worst, d);
    }
    differing += worst > 8;
  }
  const double pixels = double(a.rgb.size() / 3);
  std::printf("mean absolute difference %.4f (of 255), pixels differing by > 8: %.4f%%\n",
              sum / a.rgb.size(), 100.0 * differing / pixels);
  // scikit-image's definitions (prt/image_metrics.hpp); SSIM needs an 11 x 11 window.
  std::printf("PSNR %.6f dB\n", psnr(a, b));
  if (a.width >= 11 && a.height >= 11) std::printf("SSIM %.8f\n", ssim(a, b));
  return 0;
}

}  // namespace prt::cli
