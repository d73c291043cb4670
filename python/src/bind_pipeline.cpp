// The scene and the stages of the bake and viewing pipelines (prt/pipeline.hpp):
// the same functions the CLI composes, each callable alone.
#include <optional>

#include "bindings.hpp"
#include "long_call.hpp"
#include "prt/environment.hpp"
#include "prt/image.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt::python {

namespace {

// How a Python call runs: progress bars unless quiet; messages to `log`
// (a callable taking one str) or to the process's log on stderr.
RunOptions run_options(bool quiet, const py::object& log) {
  RunOptions options;
  options.quiet = quiet;
  if (!log.is_none()) {
    auto held = std::make_shared<py::object>(log);
    options.log = [held](const std::string& text) {
      py::gil_scoped_acquire gil;
      try {
        (*held)(text);
      } catch (py::error_already_set&) {  // a failing log callback must not stop the work
      }
    };
  }
  return options;
}

// The checks the scene's [camera] section gets, for cameras made in Python.
void check_camera(const Camera& c) {
  if (c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384)
    throw Error("camera: width and height must be in [1, 16384], not " + std::to_string(c.width) +
                " x " + std::to_string(c.height));
  if (!(c.fov_degrees > 0 && c.fov_degrees < 180))
    throw Error("camera: fov_degrees must be in (0, 180)");
  if (!c.position.allFinite() || !c.target.allFinite() || !c.up.allFinite())
    throw Error("camera: position, target and up must be finite");
  const Eigen::Vector3f view = c.target - c.position;
  if (view.norm() <= 0) throw Error("camera: the target is the position");
  if (view.normalized().cross(c.up).norm() < 1e-6)
    throw Error("camera: up is zero or along the view direction");
}

std::string traced_key(const SceneSpec& scene) {
  std::string key = scene.file.parent_path().string() + "\n" + scene.mesh.describe() + "\n" +
                    scene.transport.describe() + "\n" + scene.material.describe();
  for (const Params& part : scene.mesh_parts) key += "\n" + part.describe();  // [[mesh.add]]
  return key;
}

py::dict times_dict(const StageTimes& times) {
  py::dict out;
  for (const auto& [name, seconds] : times.stages) out[py::str(name)] = seconds;
  return out;
}

py::array_t<float> image_array(const Image& image) {
  py::array_t<float> out({image.height, image.width, 3});
  std::copy(image.rgb.begin(), image.rgb.end(), out.mutable_data());
  return out;
}

Image image_from(const py::array_t<float, py::array::c_style | py::array::forcecast>& a) {
  if (a.ndim() != 3 || a.shape(2) != 3) throw Error("an image must be a height x width x 3 array");
  Image image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
  std::copy(a.data(), a.data() + a.size(), image.rgb.begin());
  return image;
}

py::dict rendered_dict(const Rendered& r, const StageTimes* times) {
  py::dict out;
  out["image"] = image_array(r.image);
  out["vertex_radiance"] = Eigen::MatrixX3f(r.vertex_radiance);
  py::dict statistics;
  for (const auto& [key, value] : r.statistics) statistics[py::str(key)] = value;
  out["statistics"] = statistics;
  if (times) out["times"] = times_dict(*times);
  return out;
}

}  // namespace

void bind_pipeline(py::module_& m) {
  py::class_<SceneSpec>(m, "Scene",
                        "A scene file (TOML), parsed and validated with its plug-ins' parameters.")
      .def(py::init(
               [](const std::filesystem::path& file) { return SceneSpec::load(file, registry()); }),
           py::arg("file"))
      .def_static(
          "parse",
          [](const std::string& text, const std::filesystem::path& file) {
            return SceneSpec::parse(text, file, registry());
          },
          py::arg("text"), py::arg("file"),
          "A scene from TOML text; `file` names it in messages and is where relative paths "
          "resolve from.")
      .def_readonly("file", &SceneSpec::file)
      .def_readonly("text", &SceneSpec::text)
      .def_property_readonly("bake_path", &SceneSpec::bake_path)
      .def_property_readonly("image_path", &SceneSpec::image_path)
      .def_property_readonly("input_files", &SceneSpec::input_files)
      .def_property_readonly("glossy", &SceneSpec::glossy)
      .def("load_mesh", [](const SceneSpec& s) { return long_call([&] { return s.load_mesh(); }); })
      .def("directions", &SceneSpec::directions, "The [transport] direction set.")
      .def("load_environment", &SceneSpec::load_environment, "The [lighting] map.")
      .def("camera", &SceneSpec::make_camera, py::arg("mesh"), "The [camera] for this mesh.")
      .def(
          "project_light",
          [](const SceneSpec& s, const Environment& environment, const Basis& basis) {
            return long_call([&] { return s.project_light(environment, basis); });
          },
          py::arg("environment"), py::arg("basis"),
          "The environment in the basis (size() x 3), [lighting] window applied.")
      .def(
          "basis",
          [](const SceneSpec& s) {
            PluginChoice c = s.basis;
            return registry().create<Basis>(c.name, c.params, c.where);
          },
          "The scene's [basis] plug-in, created.")
      .def(
          "compressor",
          [](const SceneSpec& s) {
            PluginChoice c = s.compressor;
            return registry().create<Compressor>(c.name, c.params, c.where);
          },
          "The scene's [compressor] plug-in, created.");

  m.def(
      "trace",
      [](const SceneSpec& scene, bool quiet, const py::object& log) {
        const RunOptions options = run_options(quiet, log);
        return Traced{long_call([&] { return trace_scene(scene, options); }), traced_key(scene)};
      },
      py::arg("scene"), py::kw_only(), py::arg("quiet") = false, py::arg("log") = py::none(),
      "Traces the scene's mesh over its direction set and keeps the visibility bits (and the "
      "hits when the scene asks for bounces); pass the result to bake(traced=...).");

  m.def(
      "bake",
      [](const SceneSpec& scene, std::optional<std::filesystem::path> output, bool force,
         bool restart, bool compress, const Traced* traced, bool quiet, const py::object& log) {
        if (traced && traced->key != traced_key(scene))
          throw Error(scene.file.string() +
                      ": the rays given (traced=) were traced for another mesh, transport or "
                      "material; trace this scene (prt.trace) or leave traced out");
        RunOptions options = run_options(quiet, log);
        options.compress = compress;
        options.traced = traced ? &traced->result : nullptr;
        StageTimes times;
        BakeData data = long_call([&] {
          const BakePlan plan = plan_bake(scene, registry());
          if (!output) return bake(scene, plan, options, times);
          // As prt bake: through a checkpoint beside the file, which a rerun resumes.
          const BakeTarget target{{*output, FileKind::bake, "bake file", false, kForceKeyword},
                                  force,
                                  restart,
                                  "prt.bake " + scene.file.string() + " -> " + output->string()};
          return bake_to_file(scene, plan, target, options, times);
        });
        return py::make_tuple(std::move(data), times_dict(times));
      },
      py::arg("scene"), py::kw_only(), py::arg("output") = py::none(), py::arg("force") = false,
      py::arg("restart") = false, py::arg("compress") = true, py::arg("traced") = nullptr,
      py::arg("quiet") = false, py::arg("log") = py::none());

  m.def(
      "compress",
      [](const TransferSignal& signal, const Compressor& compressor, const Mesh* mesh) {
        check_signal_and_mesh(signal, mesh);
        return long_call([&] {
          Stopwatch clock;
          CompressedTransfer c = compressor.encode(signal, mesh);
          const double seconds = clock.seconds();
          c.validate(signal.vertices());
          return std::pair{c, measure(signal, c, mesh, seconds)};
        });
      },
      py::arg("signal"), py::arg("compressor"), py::arg("mesh") = nullptr,
      "Encodes a transfer: (compressed form, report).");

  py::class_<ViewTransfer>(m, "View",
                           "Glossy transfer folded toward one camera: one light-space vector "
                           "t_p per vertex (Relighting.view).")
      .def_property_readonly("light_space", &ViewTransfer::light_space,
                             "v x n_L: row p is t_p = M_p^T y(v_p).")
      .def_property_readonly("vertices", &ViewTransfer::vertices);

  py::class_<Relighting>(m, "Relighting",
                         "What viewing a bake needs, made once: relight it for any light, "
                         "camera and encoding.")
      .def(py::init([](const SceneSpec& scene, const BakeData& data) {
             return std::make_unique<Relighting>(scene, data, registry());
           }),
           py::arg("scene"), py::arg("data"), py::keep_alive<1, 2>(), py::keep_alive<1, 3>())
      .def(
          "light",
          [](const Relighting& r, const Environment& e) {
            return long_call([&] { return r.light(e); });
          },
          py::arg("environment"), "The light vector (size() x 3) of an environment.")
      .def(
          "relight",
          [](const Relighting& r, const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
             const Camera& camera) {
            check_camera(camera);
            r.check_inputs(transfer, light);
            return long_call([&] {
              return Eigen::MatrixX3f(r.relight(transfer, light, camera).vertex_radiance);
            });
          },
          py::arg("transfer"), py::arg("light"), py::arg("camera"),
          "Radiance each vertex sends toward the camera (v x 3, albedo included).")
      .def(
          "view",
          [](const Relighting& r, const CompressedTransfer& transfer, const Camera& camera) {
            check_camera(camera);
            return long_call([&] { return r.view(transfer, camera); });
          },
          py::arg("transfer"), py::arg("camera"),
          "Glossy transfer folded toward the camera (a View), for many lights seen from one "
          "camera: relight(view, light) then costs n_L x 3 multiply-adds a vertex. None where "
          "relight(transfer, light, camera) makes other sums (diffuse or per-channel transfer, "
          "point lights).")
      .def(
          "relight",
          [](const Relighting& r, const ViewTransfer& view, const Eigen::MatrixX3d& light) {
            return long_call([&] { return r.relight(view, light); });
          },
          py::arg("view"), py::arg("light"),
          "Radiance toward the view's camera (v x 3, albedo included).")
      .def(
          "render",
          [](const Relighting& r, const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
             const Camera& camera, Renderer& renderer, const Environment* background) {
            check_camera(camera);
            r.check_inputs(transfer, light);
            const Rendered out = long_call(
                [&] { return render_relit(r, renderer, transfer, light, camera, background); });
            return rendered_dict(out, nullptr);
          },
          py::arg("transfer"), py::arg("light"), py::arg("camera"), py::arg("renderer"),
          py::arg("background") = nullptr,
          "An image (dict: image, vertex_radiance, statistics) of `transfer` relit.");

  m.def(
      "create_renderer",
      [](const std::string& name, const py::kwargs& kwargs) {
        const std::string owner = "prt.create_renderer(\"" + name + "\")";
        Params params = params_from_kwargs(kwargs, owner);
        return registry().create<Renderer>(name, params, SourceLocation{owner});
      },
      py::arg("name"));

  m.def(
      "render",
      [](const SceneSpec& scene, const BakeData& data, bool quiet, const py::object& log) {
        const RunOptions options = run_options(quiet, log);
        StageTimes times;
        const Rendered out =
            long_call([&] { return render(scene, data, registry(), times, options); });
        return rendered_dict(out, &times);
      },
      py::arg("scene"), py::arg("data"), py::kw_only(), py::arg("quiet") = false,
      py::arg("log") = py::none(),
      "The scene's view of a bake, as `prt render` draws it: dict with image (h x w x 3 "
      "linear float32), vertex_radiance, statistics and times.");

  m.def(
      "render_ground_truth",
      [](const SceneSpec& scene, const Mesh* mesh, bool quiet, const py::object& log) {
        const RunOptions options = run_options(quiet, log);
        StageTimes times;
        const Rendered out = long_call([&] {
          const Mesh loaded = mesh ? Mesh{} : scene.load_mesh();
          return render_ground_truth(scene, mesh ? *mesh : loaded, registry(), options, times);
        });
        return rendered_dict(out, &times);
      },
      py::arg("scene"), py::arg("mesh") = nullptr, py::kw_only(), py::arg("quiet") = false,
      py::arg("log") = py::none(),
      "The Monte Carlo ground truth of the scene, as `prt render --ground-truth` draws it.");

  m.def(
      "ground_truth_vertices",
      [](const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
         const Camera& camera, bool quiet) {
        check_camera(camera);
        if (mesh.vertex_count() == 0)
          throw Error("ground_truth_vertices: the mesh has no vertices");
        const RunOptions options = run_options(quiet, py::none());
        return long_call([&] {
          return Eigen::MatrixX3f(ground_truth_vertices(scene, mesh, lighting, camera, options));
        });
      },
      py::arg("scene"), py::arg("mesh"), py::arg("lighting"), py::arg("camera"), py::kw_only(),
      py::arg("quiet") = false, "Monte Carlo radiance per vertex toward the camera (v x 3).");

  m.def(
      "reference_radiance",
      [](const SceneSpec& scene, const Mesh& mesh, const Environment& lighting,
         const Camera& camera, bool quiet, const std::optional<std::filesystem::path>& cache) {
        check_camera(camera);
        if (mesh.vertex_count() == 0) throw Error("reference_radiance: the mesh has no vertices");
        const RunOptions options = run_options(quiet, py::none());
        const std::optional<ReferenceCache> kept =
            cache ? std::optional<ReferenceCache>(ReferenceCache(*cache)) : std::nullopt;
        const Reference r = long_call([&] {
          return reference_radiance(scene, mesh, lighting, camera, options,
                                    kept ? &*kept : nullptr);
        });
        py::dict out;
        out["radiance"] = Eigen::MatrixX3f(r.radiance);
        out["standard_error"] = Eigen::MatrixX3f(r.standard_error);
        out["noise_floor"] = r.noise_floor();
        out["samples"] = r.samples;
        out["batches"] = r.batches;
        out["cached"] = r.cached.empty() ? py::object(py::none()) : py::cast(r.cached.string());
        return out;
      },
      py::arg("scene"), py::arg("mesh"), py::arg("lighting"), py::arg("camera"), py::kw_only(),
      py::arg("quiet") = false, py::arg("cache") = py::none(),
      "The Monte Carlo reference with its error bar, as `prt render --compare` measures "
      "against: dict with radiance and standard_error (v x 3), noise_floor (the standard "
      "error's per-vertex RMS), samples, batches, and cached (the file it was read from, or "
      "None). cache: a folder of references to reuse and keep (as --cache).");

  m.def(
      "write_png",
      [](const py::array_t<float, py::array::c_style | py::array::forcecast>& image,
         const std::filesystem::path& file, float exposure, bool force) {
        check_output({file, FileKind::png, "image", false, kForceKeyword}, {}, force);
        write_png(image_from(image), file, exposure);
      },
      py::arg("image"), py::arg("file"), py::arg("exposure") = 1.0f, py::arg("force") = false,
      "Writes a linear h x w x 3 image as an sRGB PNG (as prt render does).");
}

}  // namespace prt::python
