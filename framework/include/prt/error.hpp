// Errors thrown by the framework and by plug-ins. Only `main` decides to exit.
#pragma once
#include <cstddef>
#include <filesystem>
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
  // Messages longer than kMaxMessage characters keep their start and end
  // (a 10^6-character key echoed back is not a readable line).
  explicit Error(const std::string& message) : std::runtime_error(bounded(message)) {}
  Error(const SourceLocation& where, const std::string& message)
      : std::runtime_error(bounded(format(where, message))) {}
  ~Error() override;

  static constexpr std::size_t kMaxMessage = 2000;

 private:
  static std::string format(const SourceLocation& where, const std::string& message);
  static std::string bounded(const std::string& message);
};

// `value` for quoting in a message: at most `limit` characters, the middle
// elided with a count of what was left out.
std::string elide(const std::string& value, std::size_t limit = 80);

// A refusal in the one documented form, "place: error: message" (place is a
// file, file:line or file:line:col), or "error: message" where there is none.
std::string error_line(const std::string& what);

// "PATH: cannot create directories: Permission denied" from a
// std::filesystem error (whose own text puts the path last, in brackets).
std::string filesystem_message(const std::filesystem::filesystem_error& error);

// For a main's catch (...): the exception in flight as one such line (an
// out-of-memory included, never a bare std:: text).
std::string current_error_line();

}  // namespace prt
