// Work that a library defect must not be able to take this process down
// with: it runs in a forked child, and only its verdict comes back.
#pragma once
#include <cstddef>
#include <exception>
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

// What a child that parses untrusted input may use: address space beyond
// what this process maps now, processor seconds (a parser's endless loop
// ends), and no core file and no file writes.
// `idle_seconds`: the longest the parent waits for the child's next bytes
// (a child stuck without using processor time).
struct ChildLimits {
  double memory_bytes = 0;
  double cpu_seconds = 0;
  double idle_seconds = 0;
};

// Thrown by a `consume` that finds the child's stream ended early.
struct ChildStreamEnded : std::exception {
  const char* what() const noexcept override { return "the stream ended early"; }
};

// Thrown by a `consume` that waited longer than its limits' idle_seconds.
struct ChildSilent : std::exception {
  const char* what() const noexcept override { return "the child sent nothing"; }
};

// Reads exactly `size` bytes of the child's stream: ChildStreamEnded at its
// end, ChildSilent after `idle_seconds` (> 0) without a byte.
void read_from_child(int fd, void* data, std::size_t size, double idle_seconds);

// Runs `produce` in a forked child under `limits`, writing to the descriptor
// it is given, while `consume` reads the other end here: values cross, the
// parser's failures do not. An exception from `consume` ends the child and
// passes on; a stream that ends early (ChildStreamEnded) becomes an Error
// naming `what` and how the child ended (a signal, the processor-time limit).
// Where no child can be forked this throws: parsing the input here is what
// the child exists to avoid.
void exchange_with_child(const std::string& what, const ChildLimits& limits,
                         const std::function<void(int)>& produce,
                         const std::function<void(int)>& consume);

}  // namespace prt
