#include "long_call.hpp"

#include <pybind11/stl.h>

#include <csignal>
#include <memory>
#include <thread>

#include "prt/progress.hpp"

namespace prt::python {

namespace {

std::thread::id main_thread;
py::object* progress_callback_ = nullptr;  // owned; touched with the GIL held
py::object* pending_exception = nullptr;   // the callback's exception, to re-raise
int depth = 0;                             // nested long calls (with the GIL)
struct sigaction previous_sigint {};

void on_sigint(int) {
  Progress::request_interrupt();  // async-signal-safe: one atomic store
  // And Python's own flag (async-signal-safe too): a Python plug-in waiting
  // in a system call (time.sleep, a read) sees EINTR, runs Python's handler
  // and raises KeyboardInterrupt at once instead of when it returns.
  PyErr_SetInterruptEx(SIGINT);
}

void deliver(const ProgressReport& report) {
  py::gil_scoped_acquire gil;
  if (!progress_callback_ || progress_callback_->is_none()) return Progress::draw_bar(report);
  try {
    py::dict r;
    r["label"] = report.label;
    r["unit"] = report.unit;
    r["done"] = report.done;
    r["total"] = report.total;
    r["rate"] = report.rate;
    r["elapsed"] = report.elapsed;
    r["eta"] = report.eta;
    r["final"] = report.final;
    (*progress_callback_)(r);
  } catch (py::error_already_set& e) {
    // The callback failed (or saw KeyboardInterrupt): stop the work, then
    // raise its exception in the caller.
    if (!pending_exception) pending_exception = new py::object(e.value());
    Progress::request_interrupt();
  }
}

}  // namespace

void remember_main_thread() {
  main_thread = std::this_thread::get_id();
}

bool long_call_active() {
  return depth > 0;
}

py::object progress_callback() {
  return progress_callback_ ? *progress_callback_ : py::none();
}

void set_progress_callback(py::object callback) {
  delete progress_callback_;
  progress_callback_ = callback.is_none() ? nullptr : new py::object(std::move(callback));
}

LongCallScope::LongCallScope() {
  if (depth++ > 0) return;
  active_ = true;
  Progress::clear_interrupt();
  delete pending_exception;
  pending_exception = nullptr;
  Progress::set_sink(deliver);
  // Python's own SIGINT handler only sets a flag that the interpreter checks
  // between bytecodes, which never run while C++ works: ours stops the work.
  // Only where Python's own handler is in place: a user who ignores or
  // handles SIGINT keeps their choice.
  const py::module_ signal = py::module_::import("signal");
  if (std::this_thread::get_id() == main_thread &&
      signal.attr("getsignal")(signal.attr("SIGINT")).is(signal.attr("default_int_handler"))) {
    installed_ = true;
    struct sigaction action {};
    action.sa_handler = on_sigint;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_sigint);
  }
}

LongCallScope::~LongCallScope() {
  --depth;
  if (!active_) return;
  if (installed_) {
    sigaction(SIGINT, &previous_sigint, nullptr);
    // The Ctrl-C was delivered as this call's KeyboardInterrupt: clear
    // Python's flag, or it would raise a second one at the next line.
    if (std::this_thread::get_id() == main_thread) PyOS_InterruptOccurred();
  }
  Progress::set_sink(nullptr);
  Progress::clear_interrupt();
}

void LongCallScope::rethrow_pending() {
  if (!active_) return;
  if (pending_exception) {
    py::object exception = *pending_exception;
    delete pending_exception;
    pending_exception = nullptr;
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exception.ptr())), exception.ptr());
    throw py::error_already_set();
  }
  if (Progress::interrupt_requested()) throw Interrupted{};
}

}  // namespace prt::python
