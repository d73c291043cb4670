#include "python_plugins.hpp"

#include "long_call.hpp"
#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt::python {

namespace {

// "basis \"zonal\" (Python class Zonal)".
std::string label_of(const py::handle& self, const char* kind) {
  const std::string name = py::hasattr(self, "plugin_name")
                               ? std::string(py::str(self.attr("plugin_name")))
                               : std::string("?");
  return std::string(kind) + " \"" + name + "\" (Python class " +
         std::string(py::str(self.get_type().attr("__name__"))) + ")";
}

// Calls the Python override of `method` (the GIL held), turning a Python
// exception into one prt::Error naming the plug-in and the method.
template <class Interface>
py::object call_override(const Interface* self, const char* kind, const char* method,
                         const py::function& override, py::args args = py::args()) {
  try {
    return override(*args);
  } catch (py::error_already_set& e) {
    if (e.matches(PyExc_KeyboardInterrupt)) {
      if (!long_call_active()) throw;  // no work to stop: Python sees its own exception
      Progress::request_interrupt();
      throw Error("interrupted");
    }
    throw Error(label_of(py::cast(self), kind) + ": " + method + "() raised " + e.what());
  }
}

template <class Result, class Interface>
Result cast_result(const Interface* self, const char* kind, const char* method,
                   const py::object& value) {
  if (value.is_none())
    throw Error(label_of(py::cast(self), kind) + ": " + method + "() returned None");
  if constexpr (std::is_same_v<Result, bool>)
    if (!py::isinstance<py::bool_>(value) &&
        !py::isinstance(value, py::module_::import("numpy").attr("bool_")))
      throw Error(label_of(py::cast(self), kind) + ": " + method + "() returned a " +
                  std::string(py::str(value.get_type().attr("__name__"))) +
                  "; expected True or False");
  try {
    return value.cast<Result>();
  } catch (const std::exception&) {  // cast_error, reference_cast_error
    throw Error(label_of(py::cast(self), kind) + ": " + method + "() returned a " +
                std::string(py::str(value.get_type().attr("__name__"))) +
                ", which is not what the interface expects (docs/python.md)");
  }
}

void check_shape(const Basis* self, const char* method, const Eigen::MatrixXd& m, Eigen::Index rows,
                 Eigen::Index cols) {
  if (m.rows() != rows || m.cols() != cols)
    throw Error(label_of(py::cast(self), "basis") + ": " + method + "() returned a " +
                std::to_string(m.rows()) + " x " + std::to_string(m.cols()) + " array; expected " +
                std::to_string(rows) + " x " + std::to_string(cols));
  if (!m.allFinite())
    throw Error(label_of(py::cast(self), "basis") + ": " + method +
                "() returned NaN or infinite values");
}

}  // namespace

#define PRT_OVERRIDE(Interface, kind, method) \
  py::gil_scoped_acquire gil;                 \
  const py::function override = py::get_override(static_cast<const Interface*>(this), method)

int PyBasis::size() const {
  PRT_OVERRIDE(Basis, "basis", "size");
  if (!override) throw Error(label_of(py::cast(this), "basis") + ": defines no size()");
  const int n =
      cast_result<int>(this, "basis", "size", call_override(this, "basis", "size", override));
  if (n < 1)
    throw Error(label_of(py::cast(this), "basis") + ": size() returned " + std::to_string(n));
  return n;
}

Domain PyBasis::domain() const {
  PRT_OVERRIDE(Basis, "basis", "domain");
  if (!override) return Basis::domain();
  const std::string d = cast_result<std::string>(this, "basis", "domain",
                                                 call_override(this, "basis", "domain", override));
  if (d == "sphere") return Domain::sphere;
  if (d == "hemisphere") return Domain::hemisphere;
  throw Error(label_of(py::cast(this), "basis") + ": domain() returned \"" + d +
              "\"; expected \"sphere\" or \"hemisphere\"");
}

bool PyBasis::orthonormal() const {
  PRT_OVERRIDE(Basis, "basis", "orthonormal");
  if (!override) return false;
  return cast_result<bool>(this, "basis", "orthonormal",
                           call_override(this, "basis", "orthonormal", override));
}

Eigen::MatrixXd PyBasis::evaluate(const Directions& directions) const {
  const int n = size();
  PRT_OVERRIDE(Basis, "basis", "evaluate");
  if (!override) throw Error(label_of(py::cast(this), "basis") + ": defines no evaluate()");
  const py::array_t<double> d = py::cast(directions);
  auto m = cast_result<Eigen::MatrixXd>(
      this, "basis", "evaluate",
      call_override(this, "basis", "evaluate", override, py::make_tuple(d)));
  check_shape(this, "evaluate", m, directions.rows(), n);
  return m;
}

Eigen::MatrixXd PyBasis::projection_matrix(const DirectionSet& set) const {
  {
    PRT_OVERRIDE(Basis, "basis", "projection_matrix");
    if (override) {
      auto m =
          cast_result<Eigen::MatrixXd>(this, "basis", "projection_matrix",
                                       call_override(this, "basis", "projection_matrix", override,
                                                     py::make_tuple(py::cast(DirectionSet(set)))));
      check_shape(this, "projection_matrix", m, set.size(), size());
      return m;
    }
  }
  return Basis::projection_matrix(set);
}

Eigen::MatrixXd PyBasis::project(const Eigen::MatrixXd& samples, const DirectionSet& set) const {
  {
    PRT_OVERRIDE(Basis, "basis", "project");
    if (override) {
      auto m = cast_result<Eigen::MatrixXd>(
          this, "basis", "project",
          call_override(this, "basis", "project", override,
                        py::make_tuple(py::cast(samples), py::cast(DirectionSet(set)))));
      check_shape(this, "project", m, samples.rows(), size());
      return m;
    }
  }
  return Basis::project(samples, set);
}

bool PyBasis::can_rotate() const {
  PRT_OVERRIDE(Basis, "basis", "rotation_matrix");
  return static_cast<bool>(override);
}

Eigen::MatrixXd PyBasis::rotation_matrix(const Eigen::Matrix3d& rotation) const {
  {
    PRT_OVERRIDE(Basis, "basis", "rotation_matrix");
    if (override) {
      auto m = cast_result<Eigen::MatrixXd>(
          this, "basis", "rotation_matrix",
          call_override(this, "basis", "rotation_matrix", override,
                        py::make_tuple(py::cast(Eigen::Matrix3d(rotation)))));
      check_shape(this, "rotation_matrix", m, size(), size());
      return m;
    }
  }
  return Basis::rotation_matrix(rotation);
}

std::vector<int> PyBasis::coefficient_bands() const {
  PRT_OVERRIDE(Basis, "basis", "coefficient_bands");
  if (!override) return {};
  auto bands =
      cast_result<std::vector<int>>(this, "basis", "coefficient_bands",
                                    call_override(this, "basis", "coefficient_bands", override));
  if (!bands.empty() && static_cast<int>(bands.size()) != size())
    throw Error(label_of(py::cast(this), "basis") + ": coefficient_bands() returned " +
                std::to_string(bands.size()) + " bands for " + std::to_string(size()) +
                " coefficients");
  return bands;
}

std::optional<DirectionSet> PyBasis::native_directions() const {
  PRT_OVERRIDE(Basis, "basis", "native_directions");
  if (!override) return std::nullopt;
  return cast_result<std::optional<DirectionSet>>(
      this, "basis", "native_directions",
      call_override(this, "basis", "native_directions", override));
}

bool PyBasis::can_fit() const {
  PRT_OVERRIDE(Basis, "basis", "fit");
  return static_cast<bool>(override);
}

void PyBasis::fit(const FitData& data) {
  PRT_OVERRIDE(Basis, "basis", "fit");
  if (!override) return;
  py::dict d;
  // Copies: a fitted basis may keep them, and the caller's live only for this call.
  if (data.mesh) d["mesh"] = py::cast(Mesh(*data.mesh));
  if (data.directions) d["directions"] = py::cast(DirectionSet(*data.directions));
  if (data.visibility) d["visibility"] = visibility_array(*data.visibility);
  call_override(this, "basis", "fit", override, py::make_tuple(d));
}

BasisState PyBasis::save() const {
  PRT_OVERRIDE(Basis, "basis", "save");
  if (!override) return {};
  const auto state = cast_result<std::map<std::string, Eigen::MatrixXd>>(
      this, "basis", "save", call_override(this, "basis", "save", override));
  return {state};
}

void PyBasis::load(const BasisState& state) {
  PRT_OVERRIDE(Basis, "basis", "load");
  if (!override) return;
  call_override(this, "basis", "load", override, py::make_tuple(py::cast(state.matrices)));
}

CompressedTransfer PyCompressor::encode(const TransferSignal& signal, const Mesh* mesh) const {
  PRT_OVERRIDE(Compressor, "compressor", "encode");
  if (!override) throw Error(label_of(py::cast(this), "compressor") + ": defines no encode()");
  const bool stores_exactly = exact();
  for (Eigen::Index p = 0; p < signal.vertices() && !stores_exactly; ++p)  // as C++ ones refuse it
    if (!signal.coefficients.row(p).allFinite())
      throw Error(label_of(py::cast(this), "compressor") + ": the transfer of vertex " +
                  std::to_string(p) + " is not finite");
  // Copies owned by Python: a plug-in may keep its arguments past the call
  // (the caller's signal and mesh do not live that long). A signal kept on
  // disk shares its file, so only an in-memory signal costs its size again.
  py::object signal_copy = py::cast(TransferSignal(signal));
  py::object mesh_copy = mesh ? py::cast(Mesh(*mesh)) : py::none();
  auto c = cast_result<CompressedTransfer>(this, "compressor", "encode",
                                           call_override(this, "compressor", "encode", override,
                                                         py::make_tuple(signal_copy, mesh_copy)));
  try {
    c.validate(signal.vertices());
    if (c.dimension != signal.dimension())
      throw Error("its dimension is " + std::to_string(c.dimension) + ", the signal's " +
                  std::to_string(signal.dimension()));
  } catch (const Error& e) {
    throw Error(label_of(py::cast(this), "compressor") +
                ": encode() returned an inconsistent form: " + e.what());
  }
  return c;
}

bool PyCompressor::exact() const {
  PRT_OVERRIDE(Compressor, "compressor", "exact");
  if (!override) return false;
  return cast_result<bool>(this, "compressor", "exact",
                           call_override(this, "compressor", "exact", override));
}

}  // namespace prt::python
