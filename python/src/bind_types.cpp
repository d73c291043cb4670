// The framework's value types as Python classes. Arrays are numpy views of
// the C++ storage (no copy) when read; assigning an array copies it in.
#include "bindings.hpp"
#include "long_call.hpp"
#include "prt/bake_file.hpp"
#include "prt/camera.hpp"
#include "prt/compressor.hpp"
#include "prt/direction_set.hpp"
#include "prt/environment.hpp"
#include "prt/mesh.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/transport.hpp"

namespace prt::python {

namespace {

using RowsF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// v x 3 view of a vector of Vector3f (contiguous: 3 floats each).
py::array_t<float> vectors_view(const std::vector<Eigen::Vector3f>& v, py::handle owner) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  return view(v.empty() ? nullptr : v.front().data(), static_cast<py::ssize_t>(v.size()), 3, owner);
}

std::vector<Eigen::Vector3f> vectors_from(const RowsF& a, const char* what) {
  if (a.cols() != 3) throw Error(std::string(what) + ": expected an n x 3 array");
  std::vector<Eigen::Vector3f> out(a.rows());
  for (Eigen::Index i = 0; i < a.rows(); ++i) out[i] = a.row(i).transpose();
  return out;
}

template <class T>
py::array_t<T> vector_view(const std::vector<T>& v, py::handle owner) {
  return read_only(py::array_t<T>({static_cast<py::ssize_t>(v.size())},
                                  {static_cast<py::ssize_t>(sizeof(T))}, v.data(), owner));
}

template <class T>
std::vector<T> vector_from(const py::array_t<T, py::array::c_style | py::array::forcecast>& a) {
  if (a.ndim() != 1) throw Error("expected a one-dimensional array");
  return std::vector<T>(a.data(), a.data() + a.size());
}

py::dict metrics_dict(const std::map<std::string, double>& metrics) {
  py::dict out;
  for (const auto& [key, value] : metrics) out[py::str(key)] = value;
  return out;
}

py::dict state_dict(const BasisState& state) {
  py::dict out;
  for (const auto& [key, value] : state.matrices) out[py::str(key)] = value;
  return out;
}

[[maybe_unused]] BasisState state_from(const py::dict& d) {
  BasisState state;
  for (const auto& [key, value] : d) state.matrices[py::str(key)] = value.cast<Eigen::MatrixXd>();
  return state;
}

}  // namespace

py::array_t<std::uint8_t> visibility_array(const VisibilityBits& bits) {
  py::array_t<std::uint8_t> out(
      {static_cast<py::ssize_t>(bits.vertices()), static_cast<py::ssize_t>(bits.directions())});
  auto a = out.mutable_unchecked<2>();
  for (std::size_t v = 0; v < bits.vertices(); ++v)
    for (std::size_t d = 0; d < bits.directions(); ++d) a(v, d) = bits.get(v, d);
  return out;
}

void check_signal_and_mesh(const TransferSignal& signal, const Mesh* mesh) {
  if (signal.vertices() == 0 || signal.dimension() == 0)
    throw Error("the transfer is empty (" + std::to_string(signal.vertices()) + " x " +
                std::to_string(signal.dimension()) + ")");
  if (mesh && static_cast<Eigen::Index>(mesh->vertex_count()) != signal.vertices())
    throw Error("the mesh has " + std::to_string(mesh->vertex_count()) +
                " vertices but the transfer " + std::to_string(signal.vertices()) + " rows");
}

void bind_types(py::module_& m) {
  py::class_<Mesh>(m, "Mesh", "A triangle mesh: positions, unit normals, triangles.")
      .def(py::init([](const RowsF& positions, const py::array& triangle_array,
                       std::optional<RowsF> normals) {
             const char kind = triangle_array.dtype().kind();
             if (kind != 'i' && kind != 'u')
               throw Error("triangles: expected an integer array (vertex indices), not dtype " +
                           std::string(py::str(triangle_array.dtype())));
             const auto triangles = triangle_array.cast<
                 Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>();
             Mesh mesh;
             mesh.positions = vectors_from(positions, "positions");
             if (triangles.cols() != 3) throw Error("triangles: expected an n x 3 array");
             for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
               std::array<std::uint32_t, 3> tri{};
               for (int k = 0; k < 3; ++k) {
                 const std::int64_t index = triangles(t, k);
                 if (index < 0 || index >= static_cast<std::int64_t>(mesh.positions.size()))
                   throw Error("triangles: triangle " + std::to_string(t) + " uses vertex " +
                               std::to_string(index) + " of " +
                               std::to_string(mesh.positions.size()));
                 tri[k] = static_cast<std::uint32_t>(index);
               }
               mesh.triangles.push_back(tri);
             }
             if (normals)
               mesh.normals = vectors_from(*normals, "normals");
             else
               mesh.compute_normals();
             mesh.validate("mesh from arrays");
             return mesh;
           }),
           py::arg("positions"), py::arg("triangles"), py::arg("normals") = py::none(),
           "A mesh from arrays (normals computed from the triangles when not given).")
      .def_static(
          "load", [](const std::filesystem::path& file) { return load_mesh(file); },
          py::arg("file"), "Loads an OFF, PLY or OBJ file.")
      .def_property_readonly(
          "positions",
          [](py::object self) { return vectors_view(self.cast<const Mesh&>().positions, self); })
      .def_property_readonly(
          "normals",
          [](py::object self) { return vectors_view(self.cast<const Mesh&>().normals, self); })
      .def_property_readonly("triangles",
                             [](py::object self) {
                               const auto& t = self.cast<const Mesh&>().triangles;
                               return view<std::uint32_t>(t.empty() ? nullptr : t.front().data(),
                                                          static_cast<py::ssize_t>(t.size()), 3,
                                                          self);
                             })
      .def_property_readonly(
          "uvs",
          [](const Mesh& mesh) {
            py::array_t<float> out({py::ssize_t(mesh.uvs.size()), py::ssize_t(2)});
            auto view = out.mutable_unchecked<2>();
            for (std::size_t v = 0; v < mesh.uvs.size(); ++v)
              for (int c = 0; c < 2; ++c) view(py::ssize_t(v), c) = mesh.uvs[v][c];
            return out;
          },
          "(vertices, 2) texture coordinates of the texel atlas; (0, 2) without one")
      .def_property_readonly("vertex_count", &Mesh::vertex_count)
      .def_property_readonly("triangle_count", &Mesh::triangle_count)
      .def("__repr__", [](const Mesh& mesh) {
        return "<prt.Mesh " + std::to_string(mesh.vertex_count()) + " vertices, " +
               std::to_string(mesh.triangle_count()) + " triangles>";
      });

  py::class_<DirectionSet>(m, "DirectionSet",
                           "Directions over the sphere with solid-angle weights.")
      .def(py::init([](const Directions& directions, const Eigen::VectorXd& weights,
                       const std::string& kind) {
             if (directions.rows() != weights.size())
               throw Error("DirectionSet: " + std::to_string(directions.rows()) +
                           " directions but " + std::to_string(weights.size()) + " weights");
             if (!directions.allFinite() || !weights.allFinite())
               throw Error("DirectionSet: directions and weights must be finite");
             return DirectionSet{kind, directions, weights};
           }),
           py::arg("directions"), py::arg("weights"), py::arg("kind") = "custom")
      .def_static("fibonacci", &DirectionSet::fibonacci, py::arg("count"))
      .def_static("stratified", &DirectionSet::stratified, py::arg("count"), py::arg("seed") = 1)
      .def_static("cubemap", &DirectionSet::cubemap, py::arg("resolution"))
      .def_readonly("kind", &DirectionSet::kind)
      .def_property_readonly("directions",
                             [](py::object self) {
                               const auto& d = self.cast<const DirectionSet&>().directions;
                               return view(d.data(), d.rows(), 3, self);
                             })
      .def_property_readonly(
          "weights",
          [](py::object self) {
            const auto& w = self.cast<const DirectionSet&>().weights;
            return read_only(py::array_t<double>({w.size()}, {sizeof(double)}, w.data(), self));
          })
      .def("__len__", &DirectionSet::size);

  py::class_<Camera>(m, "Camera", "A pinhole camera.")
      .def(py::init<>())
      .def_static("framing", &Camera::framing, py::arg("mesh"), py::arg("width") = 640,
                  py::arg("height") = 480, py::arg("fov_degrees") = 40.0f,
                  "A camera that frames the whole mesh.")
      .def_readwrite("position", &Camera::position)
      .def_readwrite("target", &Camera::target)
      .def_readwrite("up", &Camera::up)
      .def_readwrite("fov_degrees", &Camera::fov_degrees)
      .def_readwrite("width", &Camera::width)
      .def_readwrite("height", &Camera::height);

  py::class_<Environment>(m, "Environment", "Distant light: an equirectangular HDR map.")
      .def_static("load", &Environment::load, py::arg("file"), "Loads an .exr or .hdr map.")
      .def_static(
          "constant",
          [](const Eigen::Vector3f& radiance) {
            if (!radiance.allFinite() || radiance.minCoeff() < 0)
              throw Error("Environment.constant: radiance must be finite and non-negative");
            return Environment::constant(radiance);
          },
          py::arg("radiance"))
      .def_property_readonly("width", &Environment::width)
      .def_property_readonly("height", &Environment::height)
      .def_property_readonly(
          "pixels",
          [](const Environment& e) {
            // A copy, rows top first: (height, width, 3) linear RGB.
            py::array_t<float> out({e.height(), e.width(), 3});
            std::copy(e.pixels().begin(), e.pixels().end(), out.mutable_data());
            return out;
          },
          "The map's linear RGB radiance as a (height, width, 3) float32 array (a copy).")
      .def_property(
          "rotation", [](const Environment& e) { return Eigen::Matrix3d(e.rotation()); },
          [](Environment& e, const Eigen::Matrix3d& r) {
            if (!r.allFinite() ||
                (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
                r.determinant() < 0)
              throw Error("Environment.rotation: expected a rotation matrix (orthonormal, det 1)");
            e.set_rotation(r);
          },
          "Rotation of the map, a 3 x 3 matrix (the light turns, not the object); "
          "set_rotation_degrees(d) turns it about +y as [lighting] rotation does.")
      .def(
          "set_rotation_degrees",
          [](Environment& e, double degrees) {
            if (!std::isfinite(degrees)) throw Error("set_rotation_degrees: not a finite angle");
            e.set_rotation(rotation_about_up(degrees));
          },
          py::arg("degrees"), "Turns the map about +y, as the scene's [lighting] rotation.")
      .def(
          "set_intensity",
          [](Environment& e, float intensity) {
            if (!std::isfinite(intensity) || intensity < 0)
              throw Error("set_intensity: the intensity must be finite and non-negative");
            e.set_intensity(intensity);
          },
          py::arg("intensity"));

  py::class_<TransferSignal>(m, "TransferSignal",
                             "Per-vertex transfer: one row of coefficients per vertex.")
      .def(py::init([](const RowsF& coefficients, const std::string& kind, int exit_rows) {
             if (kind != "diffuse" && kind != "glossy")
               throw Error("TransferSignal: kind must be \"diffuse\" or \"glossy\", not \"" + kind +
                           "\"");
             if (exit_rows < 1 || coefficients.cols() % exit_rows != 0)
               throw Error("TransferSignal: exit_rows " + std::to_string(exit_rows) +
                           " does not divide the " + std::to_string(coefficients.cols()) +
                           " columns");
             if (coefficients.cols() == 0)
               throw Error("TransferSignal: the array has no columns (coefficients)");
             TransferSignal s;
             s.coefficients = coefficients;
             s.kind = kind;
             s.exit_rows = exit_rows;
             return s;
           }),
           py::arg("coefficients"), py::arg("kind") = "diffuse", py::arg("exit_rows") = 1)
      .def_property_readonly("coefficients",
                             [](py::object self) {  // read-only: a file's rows too
                               const auto c = self.cast<const TransferSignal&>().rows();
                               return view(c.data(), c.rows(), c.cols(), self);
                             })
      .def_readonly("kind", &TransferSignal::kind)
      .def_readonly("exit_rows", &TransferSignal::exit_rows)
      .def_readonly("channel_groups", &TransferSignal::channel_groups)
      .def_property_readonly("vertices", &TransferSignal::vertices)
      .def_property_readonly("dimension", &TransferSignal::dimension);

  py::class_<CompressedTransfer>(
      m, "CompressedTransfer",
      "The one compressed form: per vertex a cluster and weights, per cluster a mean and "
      "representatives (DESIGN section 3).")
      .def(py::init([](const std::string& compressor, Eigen::Index dimension,
                       const py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>&
                           cluster_of_vertex,
                       const RowsF& weights, const RowsF& means,
                       const std::vector<RowsF>& representatives) {
             CompressedTransfer c;
             c.compressor = compressor;
             c.dimension = dimension;
             c.cluster_of_vertex = vector_from(cluster_of_vertex);
             c.weights = weights;
             c.components = static_cast<int>(weights.cols());
             c.means = means;
             for (const auto& r : representatives) c.representatives.push_back(r);
             // The structure now (indices, shapes); values may be NaN in an exact form.
             c.validate(c.vertices(), false);
             return c;
           }),
           py::arg("compressor"), py::arg("dimension"), py::arg("cluster_of_vertex"),
           py::arg("weights"), py::arg("means"), py::arg("representatives"),
           "t_p = means[k] + weights[p, :n'_k] @ representatives[k], k = cluster_of_vertex[p].")
      .def_readonly("compressor", &CompressedTransfer::compressor)
      .def_readonly("dimension", &CompressedTransfer::dimension)
      .def_readonly("components", &CompressedTransfer::components)
      .def_property_readonly("cluster_of_vertex",
                             [](py::object self) {
                               return vector_view(
                                   self.cast<const CompressedTransfer&>().cluster_of_vertex, self);
                             })
      .def_property_readonly("weights",
                             [](py::object self) {
                               const auto& w = self.cast<const CompressedTransfer&>().weights;
                               return view(w.data(), w.rows(), w.cols(), self);
                             })
      .def_property_readonly("means",
                             [](py::object self) {
                               const auto& w = self.cast<const CompressedTransfer&>().means;
                               return view(w.data(), w.rows(), w.cols(), self);
                             })
      .def_property_readonly(
          "representatives",
          [](py::object self) {
            py::list out;
            for (const auto& r : self.cast<const CompressedTransfer&>().representatives)
              out.append(view(r.data(), r.rows(), r.cols(), self));
            return out;
          })
      .def_property_readonly("weight_index",
                             [](py::object self) {
                               return vector_view(
                                   self.cast<const CompressedTransfer&>().weight_index, self);
                             })
      .def_property_readonly("sparse", &CompressedTransfer::sparse)
      .def_property_readonly("vertices", &CompressedTransfer::vertices)
      .def_property_readonly("clusters", &CompressedTransfer::clusters)
      .def_property_readonly("statistics",
                             [](const CompressedTransfer& c) { return metrics_dict(c.statistics); })
      .def(
          "decode",
          [](const CompressedTransfer& c) {
            c.validate(c.vertices(), false);
            return c.decode();
          },
          "The v x n signal it stands for (a copy).")
      .def("stored_floats", &CompressedTransfer::stored_floats)
      .def("validate", &CompressedTransfer::validate, py::arg("vertex_count"),
           py::arg("finite") = true);
  m.def("exact_form", &exact_form, py::arg("signal"),
        "The signal as a compressed form that stores it exactly.");

  py::class_<CompressionReport>(m, "CompressionReport", "What an encode costs and loses.")
      .def_readonly("squared_error", &CompressionReport::squared_error)
      .def_readonly("vertex_error_p50", &CompressionReport::vertex_error_p50)
      .def_readonly("vertex_error_p90", &CompressionReport::vertex_error_p90)
      .def_readonly("vertex_error_p99", &CompressionReport::vertex_error_p99)
      .def_readonly("vertex_error_max", &CompressionReport::vertex_error_max)
      .def_readonly("stored_floats", &CompressionReport::stored_floats)
      .def_readonly("stored_bytes", &CompressionReport::stored_bytes)
      .def_readonly("encode_seconds", &CompressionReport::encode_seconds)
      .def_readonly("overdraw", &CompressionReport::overdraw)
      .def_readonly("clusters", &CompressionReport::clusters)
      .def_readonly("statistics", &CompressionReport::statistics)
      .def("__repr__", &CompressionReport::text);
  m.def(
      "measure",
      [](const TransferSignal& signal, const CompressedTransfer& compressed, const Mesh* mesh) {
        check_signal_and_mesh(signal, mesh);
        compressed.validate(signal.vertices());
        if (compressed.dimension != signal.dimension())
          throw Error("measure: the compressed form has " + std::to_string(compressed.dimension) +
                      " coefficients per vertex, the signal " + std::to_string(signal.dimension()));
        return long_call([&] { return measure(signal, compressed, mesh, 0); });
      },
      py::arg("signal"), py::arg("compressed"), py::arg("mesh") = nullptr,
      "Squared error, its per-vertex distribution, storage and overdraw of an encoding.");

  py::class_<Traced>(m, "Traced", "Rays traced for a scene: visibility bits (and hits).")
      .def_property_readonly("rays_cast", [](const Traced& t) { return t.result.rays_cast; })
      .def_property_readonly("trace_seconds",
                             [](const Traced& t) { return t.result.trace_seconds; })
      .def(
          "visibility", [](const Traced& t) { return visibility_array(t.result.visibility); },
          "Vertices x directions, 1 where the direction is unoccluded and above the surface "
          "(a copy, one byte per bit).");

  py::class_<PluginRecord>(m, "PluginRecord")
      .def_readonly("name", &PluginRecord::name)
      .def_readonly("version", &PluginRecord::version)
      .def_readonly("parameters", &PluginRecord::parameters)
      .def("__repr__", &one_line);

  py::class_<Receivers>(m, "Receivers",
                        "Where a bake's transfer rows are: the mesh's vertices, the texels of "
                        "its atlas, or probes on a grid (docs/receivers.md).")
      .def_readonly("kind", &Receivers::kind, "\"vertices\", \"texels\" or \"probes\"")
      .def_property_readonly(
          "width", [](const Receivers& r) { return r.atlas.width; },
          "texels: the atlas texture's width in texels")
      .def_property_readonly(
          "height", [](const Receivers& r) { return r.atlas.height; },
          "texels: the atlas texture's height in texels")
      .def_property_readonly(
          "texels",
          [](const Receivers& r) {
            py::array_t<std::uint32_t> out(py::ssize_t(r.atlas.texels.size()));
            std::copy(r.atlas.texels.begin(), r.atlas.texels.end(), out.mutable_data());
            return out;
          },
          "texels: each row's texel, y * width + x (uv [x, x+1] / width x [y, y+1] / height)")
      .def_property_readonly(
          "origin", [](const Receivers& r) { return Eigen::Vector3f(r.grid.origin); },
          "probes: position of probe (0, 0, 0)")
      .def_property_readonly(
          "spacing", [](const Receivers& r) { return r.grid.spacing; },
          "probes: distance between neighbouring probes")
      .def_property_readonly(
          "counts", [](const Receivers& r) { return r.grid.counts; },
          "probes: (x, y, z) probe counts; probe index x + nx (y + ny z)")
      .def_property_readonly(
          "positions",
          [](const Receivers& r) {
            const std::size_t n = r.points.vertex_count();
            py::array_t<float> out({py::ssize_t(n), py::ssize_t(3)});
            auto view = out.mutable_unchecked<2>();
            for (std::size_t p = 0; p < n; ++p)
              for (int a = 0; a < 3; ++a) view(py::ssize_t(p), a) = r.points.positions[p][a];
            return out;
          },
          "probes and texels: (rows, 3) positions, in transfer row order")
      .def_property_readonly(
          "valid",
          [](const Receivers& r) {
            py::array_t<bool> out(py::ssize_t(r.valid.size()));
            std::copy(r.valid.begin(), r.valid.end(), out.mutable_data());
            return out;
          },
          "probes: False where a probe sits inside geometry (its row is zero)")
      .def_readonly("points", &Receivers::points,
                    "probes and texels: a point mesh (no triangles; texels' surface normals), one "
                    "vertex per row: the mesh to give prt.compress and prt.measure for this "
                    "transfer");

  py::class_<BakeData>(m, "BakeData", "A bake: the contents of one bake file.")
      .def_static(
          "read", [](const std::filesystem::path& file) { return read_bake(file); },
          py::arg("file"), "Reads a bake file (checked: format version, checksum, shapes).")
      .def(
          "write",
          [](const BakeData& data, const std::filesystem::path& file,
             const std::vector<std::filesystem::path>& inputs, bool force) {
            check_output({file, FileKind::bake, "bake file", false, kForceKeyword}, inputs, force);
            long_call([&] { write_bake(file, data); });
          },
          py::arg("file"), py::arg("inputs") = std::vector<std::filesystem::path>{},
          py::arg("force") = false,
          "Writes atomically; refuses to overwrite `inputs` or a file that is not a bake "
          "(unless force).")
      .def_readonly("scene_file", &BakeData::scene_file)
      .def_readonly("scene_text", &BakeData::scene_text)
      .def_readonly("basis", &BakeData::basis)
      .def_readonly("exit", &BakeData::exit)
      .def_readonly("compressor", &BakeData::compressor)
      .def_readonly("transport", &BakeData::transport)
      .def_readonly("material", &BakeData::material)
      .def_readonly("bounces", &BakeData::bounces)
      .def_readonly("mesh", &BakeData::mesh)
      .def_readonly("receivers", &BakeData::receivers)
      .def_readonly("transfer", &BakeData::transfer)
      .def_property(
          "compressed", [](const BakeData& d) { return d.compressed; },
          [](BakeData& d, const CompressedTransfer& c) {
            check_encoding(d, c, "compressed", false);
            d.compressed = c;
          },
          "The compressed form relit by render(); assign another encoding of the "
          "transfer to render it instead.")
      .def_property_readonly("basis_state",
                             [](const BakeData& d) { return state_dict(d.basis_state); })
      .def_property_readonly("metrics", [](const BakeData& d) { return metrics_dict(d.metrics); })
      .def_property_readonly("albedo", [](const BakeData& d) { return Eigen::Vector3f(d.albedo); });
}

}  // namespace prt::python
