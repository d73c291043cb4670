// How the module runs work that takes long: without the GIL (so TBB threads
// can call plug-ins written in Python and the progress callback), with
// SIGINT turned into a cooperative interruption (prt::Progress), and with
// the Python progress callback as the sink of every progress bar.
#pragma once
#include <pybind11/pybind11.h>

#include <utility>

#include "prt/error.hpp"

namespace prt::python {
namespace py = pybind11;

// Raised in Python as KeyboardInterrupt.
struct Interrupted {};

// Installs the SIGINT handler and the progress sink for its lifetime (on the
// main thread only; nested scopes do nothing).
class LongCallScope {
 public:
  LongCallScope();
  ~LongCallScope();
  LongCallScope(const LongCallScope&) = delete;
  LongCallScope& operator=(const LongCallScope&) = delete;
  // After the work: throws Interrupted if Ctrl-C was pressed, or the
  // progress callback's own exception.
  void rethrow_pending();

 private:
  bool active_ = false;
  bool installed_ = false;  // our SIGINT handler, to restore the previous one
};

// Called at import (on the main thread, where Python handles signals).
void remember_main_thread();

// Whether a long call is running (Ctrl-C then stops it cooperatively).
bool long_call_active();

// The callable that receives progress reports (None: bars on stderr).
py::object progress_callback();

// Sets the callable that receives progress reports (None: bars on stderr).
void set_progress_callback(py::object callback);

template <class Work>
auto long_call(Work&& work) {
  LongCallScope scope;
  try {
    if constexpr (std::is_void_v<decltype(work())>) {
      {
        py::gil_scoped_release release;
        work();
      }
      scope.rethrow_pending();
    } else {
      auto result = [&] {
        py::gil_scoped_release release;
        return work();
      }();
      scope.rethrow_pending();
      return result;
    }
  } catch (const Error&) {
    scope.rethrow_pending();  // an interruption unwinds as an Error("interrupted")
    throw;
  }
}

}  // namespace prt::python
