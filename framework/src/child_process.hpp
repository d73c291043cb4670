// Work that a library defect must not be able to take this process down
// with: it runs in a forked child, and only its verdict comes back.
#pragma once
#include <functional>
#include <string>

namespace prt {

// Whether this is the child of run_in_child_process.
bool in_child_process();

// The child's side: ends the child at once with `message` as its error,
// without unwinding (no destructor of a library in a failed state runs).
// Only valid inside run_in_child_process's work.
[[noreturn]] void fail_child_process(const std::string& message);

// Runs `work` in a forked child and waits for it. An exception in the child,
// or fail_child_process, comes back as prt::Error with its message; a child
// that dies by a signal is an Error that says so, naming `what`. Where no
// child can be forked (no memory for one), `work` runs here instead.
void run_in_child_process(const std::string& what, const std::function<void()>& work);

}  // namespace prt
