// Errors thrown by the framework and by plug-ins. Only `main` decides to exit.
#pragma once
#include <stdexcept>
#include <string>

namespace prt {

// Where a value came from: a file and, when known, a line and column.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;

  // "file:line:col" (parts that are unknown are left out).
  std::string str() const;
};

// An error with an optional source location, printed in compiler style:
// "scene.toml:14:9: error: basis "sh": unknown parameter ...".
//
// The destructor is the key function, defined in libprt: the vtable and
// type_info then live in the framework, not in each plug-in, so an Error
// thrown by a plug-in stays valid after the plug-in is unloaded during
// unwinding, and catch (const prt::Error&) matches across modules.
class __attribute__((visibility("default"))) Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
  Error(const SourceLocation& where, const std::string& message)
      : std::runtime_error(format(where, message)) {}
  ~Error() override;

 private:
  static std::string format(const SourceLocation& where, const std::string& message);
};

// A refusal in the one documented form, "place: error: message" (place is a
// file, file:line or file:line:col), or "error: message" where there is none.
std::string error_line(const std::string& what);

// For a main's catch (...): the exception in flight as one such line (an
// out-of-memory included, never a bare std:: text).
std::string current_error_line();

}  // namespace prt
