// The plug-in interfaces, the registry, Python plug-ins and the conformance kit.
#include <algorithm>
#include <cctype>

#include "kit.hpp"
#include "long_call.hpp"
#include "prt/direction_set.hpp"
#include "prt/memory.hpp"
#include "prt/mesh.hpp"
#include "prt/progress.hpp"
#include "prt/renderer.hpp"
#include "python_plugins.hpp"

namespace prt::python {

namespace {

PluginKind kind_from(const std::string& kind) {
  for (PluginKind k : {PluginKind::basis, PluginKind::compressor, PluginKind::renderer})
    if (kind == to_string(k)) return k;
  throw Error("unknown plug-in kind \"" + kind + "\" (basis, compressor or renderer)");
}

py::dict spec_dict(const ParamSpecRecord& spec) {
  py::dict d;
  d["name"] = std::string(spec.name);
  d["type"] = std::string(to_string(spec.type));
  d["default"] = std::string(spec.default_value);
  d["required"] = spec.required != 0;
  if (spec.type == ParamType::integer || spec.type == ParamType::real ||
      spec.type == ParamType::reals) {
    d["min"] = spec.min;
    d["max"] = spec.max;
  }
  if (spec.type == ParamType::reals) d["length"] = spec.list_length;
  d["choices"] = std::string(spec.choices);
  d["help"] = std::string(spec.help);
  return d;
}

py::dict descriptor_dict(const PluginDescriptor& d) {
  py::dict out;
  out["kind"] = std::string(to_string(d.kind()));
  out["name"] = d.name();
  out["version"] = std::string(d.info.version);
  out["description"] = std::string(d.info.description);
  out["file"] = d.file.string();
  out["python"] = static_cast<bool>(d.factory);
  py::list params;
  for (const auto& spec : d.schema().specs) params.append(spec_dict(spec));
  out["parameters"] = params;
  return out;
}

// The type names of prt.integer(...) etc. (and the schema's own names).
ParamType param_type_from(const std::string& type) {
  const std::pair<const char*, ParamType> names[] = {
      {"boolean", ParamType::boolean}, {"integer", ParamType::integer}, {"real", ParamType::real},
      {"string", ParamType::string},   {"reals", ParamType::reals},     {"path", ParamType::path}};
  for (const auto& [name, t] : names)
    if (type == name || type == to_string(t)) return t;
  throw Error("unknown parameter type \"" + type +
              "\" (boolean, integer, real, string, reals or path)");
}

bool is_identifier(const std::string& name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// What Params::validate does not check and a C++ plug-in's constexpr schema
// gets right by review: a usable name, a range, and no empty choice. The
// defaults are checked by the validator itself (record_from).
void check_spec(const std::string& plugin, const ParamSpecRecord& p) {
  const std::string where = "plug-in \"" + plugin + "\", parameter \"" + p.name + "\": ";
  if (!is_identifier(p.name) || std::string(p.name) == "plugin")
    throw Error(where + "a name must be letters, digits and _ (and not \"plugin\")");
  if (p.min > p.max) throw Error(where + "min is above max");
  const std::string choices = std::string("|") + p.choices + "|";
  if (p.choices[0] && choices.find("||") != std::string::npos)
    throw Error(where + "an empty choice");
}

void copy_field(char* dst, std::size_t capacity, const std::string& text, const std::string& what) {
  if (text.size() + 1 > capacity)
    throw Error(what + " \"" + text + "\" is longer than " + std::to_string(capacity - 1) +
                " characters");
  schema::copy_text(dst, capacity, text.c_str());
}

// The info record of a Python plug-in, from what prt.register_* collected.
PluginInfoRecord record_from(PluginKind kind, const std::string& name, const py::list& specs,
                             const std::string& description, const std::string& version) {
  PluginInfoRecord r{};
  r.abi_version = PRT_ABI_VERSION;
  r.record_size = sizeof r;
  r.kind = kind;
  copy_field(r.name, sizeof r.name, name, "plug-in name");
  copy_field(r.version, sizeof r.version, version, "version");
  copy_field(r.build_key, sizeof r.build_key, host_build_key(), "build key");
  copy_field(r.description, sizeof r.description, description, "description");
  if (specs.size() > kMaxParams)
    throw Error("plug-in \"" + name + "\" declares " + std::to_string(specs.size()) +
                " parameters; at most " + std::to_string(kMaxParams) + " are allowed");
  r.param_count = static_cast<std::uint32_t>(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const py::dict s = specs[i];
    ParamSpecRecord& p = r.params[i];
    const std::string key = s["name"].cast<std::string>();
    copy_field(p.name, sizeof p.name, key, "parameter name");
    p.type = param_type_from(s["type"].cast<std::string>());
    p.required = s.contains("required") && s["required"].cast<bool>();
    p.list_length = s.contains("length") ? s["length"].cast<std::uint32_t>() : 0;
    p.min = s.contains("min") ? s["min"].cast<double>() : -schema::kHuge;
    p.max = s.contains("max") ? s["max"].cast<double>() : schema::kHuge;
    copy_field(p.default_value, sizeof p.default_value,
               s.contains("default") ? s["default"].cast<std::string>() : "", "default of " + key);
    copy_field(p.choices, sizeof p.choices,
               s.contains("choices") ? s["choices"].cast<std::string>() : "", "choices of " + key);
    copy_field(p.help, sizeof p.help, s.contains("help") ? s["help"].cast<std::string>() : "",
               "help of " + key);
    check_spec(name, p);
  }
  // Every default (type, range, choice) through the validator that would
  // otherwise refuse it at the first create: refused here, at registration.
  ParamSchema schema = PluginDescriptor{{}, r, {}}.schema();
  for (auto& spec : schema.specs) spec.required = 0;  // the defaults only
  Params().validate(schema);
  return r;
}

// A Python object kept alive by C++ and released with the GIL (never after
// the interpreter has gone: then it is left to the process's end).
std::shared_ptr<py::object> keep(py::object object) {
  return std::shared_ptr<py::object>(new py::object(std::move(object)), [](py::object* o) {
    if (!Py_IsInitialized()) return;
    py::gil_scoped_acquire gil;
    delete o;
  });
}

void register_plugin(const std::string& kind_name, const std::string& name, py::object cls,
                     const py::list& specs, const std::string& description,
                     const std::string& version, const std::string& origin) {
  const PluginKind kind = kind_from(kind_name);
  if (long_call_active())  // work running (e.g. a bake calling this plug-in) reads the registry
    throw Error("cannot register plug-in \"" + name + "\" while a bake, render or check runs");
  registry();  // scanned first, so that a library plug-in's name is refused
  const py::object interface =
      py::module_::import("prt._prt").attr(kind == PluginKind::basis ? "Basis" : "Compressor");
  if (kind == PluginKind::renderer)
    throw Error("renderers cannot be written in Python (they draw every frame)");
  if (!PyType_Check(cls.ptr()) || !PyObject_IsSubclass(cls.ptr(), interface.ptr()))
    throw Error(origin + ": a " + kind_name + " plug-in must be a class deriving from prt." +
                (kind == PluginKind::basis ? "Basis" : "Compressor"));
  const PluginInfoRecord record = record_from(kind, name, specs, description, version);
  auto held = keep(cls);
  register_in_process(record, origin, [held, kind, origin](Params& params) {
    py::gil_scoped_acquire gil;
    py::object instance;
    try {
      instance = (*held)(**params_to_dict(params));
    } catch (py::error_already_set& e) {
      if (!long_call_active() || !e.matches(PyExc_KeyboardInterrupt))
        throw Error(origin + ": constructor raised " + e.what());
      Progress::request_interrupt();
      throw Error("interrupted");
    }
    PluginObject* raw = nullptr;
    try {
      raw = kind == PluginKind::basis ? static_cast<PluginObject*>(instance.cast<Basis*>())
                                      : static_cast<PluginObject*>(instance.cast<Compressor*>());
    } catch (const py::cast_error&) {
      throw Error(origin + ": the constructor did not make a prt." +
                  (kind == PluginKind::basis ? std::string("Basis") : std::string("Compressor")) +
                  " (does __init__ call super().__init__()?)");
    }
    if (!raw)
      throw Error(origin +
                  ": the object is not initialised (does __init__ call super().__init__()?)");
    auto alive = keep(instance);
    return std::shared_ptr<PluginObject>(raw, [alive](PluginObject*) {});
  });
}

// A call that returns rows x cols doubles: refused before it starts when the
// result cannot fit in the memory available, and an allocation that fails
// inside it named, as prt.Error rather than a bare MemoryError.
template <class Work>
auto returning_doubles(const char* method, Eigen::Index rows, Eigen::Index cols, Work&& work) {
  const double bytes = double(rows) * double(cols) * sizeof(double);
  const std::string what = std::string(method) + ": a " + std::to_string(rows) + " x " +
                           std::to_string(cols) + " array of doubles (" + gigabytes(bytes) + ")";
  const double available = available_memory();
  if (bytes > available)
    throw Error(what + " is more than the " + gigabytes(available) +
                " of memory available; ask for fewer rows or a smaller basis");
  try {
    return work();
  } catch (const std::bad_alloc&) {
    throw Error(what + ": out of memory while computing it (the basis's own work needs more)");
  }
}

}  // namespace

void bind_plugins(py::module_& m) {
  py::enum_<Domain>(m, "Domain")
      .value("sphere", Domain::sphere)
      .value("hemisphere", Domain::hemisphere);

  py::class_<Basis, PyBasis, std::shared_ptr<Basis>>(
      m, "Basis",
      "A set of functions over the sphere or hemisphere. Subclass it in Python: define size(), "
      "evaluate(directions) and orthonormal(); optionally domain(), projection_matrix(set), "
      "project(samples, set), rotation_matrix(R), coefficient_bands(), native_directions(), "
      "fit(data), save() and load(state).")
      .def(py::init<>())
      .def("size", &Basis::size)
      .def(
          "domain",
          [](const Basis& b) { return b.domain() == Domain::hemisphere ? "hemisphere" : "sphere"; })
      .def("orthonormal", &Basis::orthonormal)
      .def(
          "evaluate",
          [](const Basis& b, const Directions& d) {
            return returning_doubles("evaluate", d.rows(), b.size(),
                                     [&] { return long_call([&] { return b.evaluate(d); }); });
          },
          py::arg("directions"), "Basis values at unit directions (s x 3): s x size().")
      .def(
          "projection_matrix",
          [](const Basis& b, const DirectionSet& set) {
            return returning_doubles("projection_matrix", set.size(), b.size(), [&] {
              return long_call([&] { return b.projection_matrix(set); });
            });
          },
          py::arg("set"))
      .def(
          "project",
          [](const Basis& b, const Eigen::MatrixXd& samples, const DirectionSet& set) {
            if (samples.cols() != set.size())
              throw Error("project: samples have " + std::to_string(samples.cols()) +
                          " columns, the direction set " + std::to_string(set.size()) +
                          " directions");
            return returning_doubles("project", samples.rows(), b.size(), [&] {
              return long_call([&] { return b.project(samples, set); });
            });
          },
          py::arg("samples"), py::arg("set"),
          "Coefficients (m x size()) of m functions sampled on the set (m x s).")
      .def("can_rotate", &Basis::can_rotate)
      .def("rotation_matrix", &Basis::rotation_matrix, py::arg("rotation"))
      .def("coefficient_bands", &Basis::coefficient_bands)
      .def("native_directions", &Basis::native_directions)
      .def("approximation_terms", &Basis::approximation_terms)
      .def("can_fit", &Basis::can_fit)
      .def("save", [](const Basis& b) { return b.save().matrices; })
      .def("load", [](Basis& b, const std::map<std::string, Eigen::MatrixXd>& state) {
        b.load(BasisState{state});
      });

  py::class_<Compressor, PyCompressor, std::shared_ptr<Compressor>>(
      m, "Compressor",
      "Transfer signal -> the one compressed form. Subclass it in Python: define "
      "encode(signal, mesh) returning a prt.CompressedTransfer; optionally exact().")
      .def(py::init<>())
      .def(
          "encode",
          [](const Compressor& c, const TransferSignal& signal, const Mesh* mesh) {
            return long_call([&] { return c.encode(signal, mesh); });
          },
          py::arg("signal"), py::arg("mesh") = nullptr)
      .def("exact", &Compressor::exact);

  py::class_<Renderer, std::shared_ptr<Renderer>>(m, "Renderer");

  m.def(
      "plugins",
      [] {
        py::list out;
        for (const auto& d : registry().plugins()) out.append(descriptor_dict(d));
        return out;
      },
      "Every plug-in found: kind, name, version, description, file and parameter schema.");
  m.def(
      "plugin_problems",
      [] {
        py::list out;
        for (const auto& p : registry().problems()) out.append(p.message);
        return out;
      },
      "What was skipped on the plug-in path, one message each.");
  m.def(
      "create_basis",
      [](const std::string& name, const py::kwargs& kwargs) {
        const std::string owner = "prt.create_basis(\"" + name + "\")";
        Params params = params_from_kwargs(kwargs, owner);
        return registry().create<Basis>(name, params, SourceLocation{owner});
      },
      py::arg("name"), "A basis plug-in; keyword arguments are its parameters.");
  m.def(
      "create_compressor",
      [](const std::string& name, const py::kwargs& kwargs) {
        const std::string owner = "prt.create_compressor(\"" + name + "\")";
        Params params = params_from_kwargs(kwargs, owner);
        return registry().create<Compressor>(name, params, SourceLocation{owner});
      },
      py::arg("name"), "A compressor plug-in; keyword arguments are its parameters.");
  m.def("register_plugin", &register_plugin, py::arg("kind"), py::arg("name"), py::arg("cls"),
        py::arg("parameters"), py::arg("description"), py::arg("version"), py::arg("origin"));
  m.def(
      "unregister_plugin",
      [](const std::string& kind, const std::string& name) {
        unregister_in_process(kind_from(kind), name);
      },
      py::arg("kind"), py::arg("name"));
  m.def("unregister_all_python_plugins", [] {
    std::vector<std::pair<PluginKind, std::string>> python;
    for (const auto& d : registry().plugins())
      if (d.factory) python.emplace_back(d.kind(), d.name());
    for (const auto& [kind, name] : python) unregister_in_process(kind, name);
  });

  m.def(
      "conformance_checks",
      [](const std::string& kind) {
        std::vector<std::pair<std::string, std::string>> out;
        for (const auto& check : conformance::checks(kind_from(kind)))
          out.emplace_back(check.name, check.tags);
        return out;
      },
      py::arg("kind"), "The conformance kit's checks of a kind: (name, tags).");
  m.def(
      "run_conformance_check",
      [](const std::string& kind, const std::string& plugin, const std::string& check_name) {
        registry().find(kind_from(kind), plugin);  // an unknown name: one error, not 11
        for (const auto& check : conformance::checks(kind_from(kind)))
          if (check.name == check_name)
            return long_call([&] {
              PluginRegistry fresh(PluginRegistry::default_directories());
              return conformance::run_check(check, fresh, plugin);
            });
        throw Error("no " + kind + " conformance check named \"" + check_name + "\"");
      },
      py::arg("kind"), py::arg("plugin"), py::arg("check"),
      "Runs one check of the kit on a plug-in: its failures (empty: it passes).");
}

}  // namespace prt::python
