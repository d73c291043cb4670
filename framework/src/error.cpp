#include "prt/error.hpp"

#include <new>
#include <sstream>

namespace prt {

std::string SourceLocation::str() const {
  std::ostringstream s;
  s << file;
  if (line > 0) {
    s << ':' << line;
    if (column > 0) s << ':' << column;
  }
  return s.str();
}

Error::~Error() = default;

std::string Error::format(const SourceLocation& where, const std::string& message) {
  const std::string place = where.str();
  return place.empty() ? message : place + ": error: " + message;
}

std::string error_line(const std::string& what) {
  if (what.find(": error: ") != std::string::npos) return what;
  // "place: message", where the place (a path, maybe with :line) has no spaces.
  const auto colon = what.find(": ");
  if (colon != std::string::npos && colon > 0 && what.find_first_of(" \t\"") > colon)
    return what.substr(0, colon) + ": error: " + what.substr(colon + 2);
  return "error: " + what;
}

std::string current_error_line() {
  try {
    throw;
  } catch (const std::bad_alloc&) {
    return "error: out of memory: the scene or file needs more memory than this machine has";
  } catch (const std::exception& e) {
    return error_line(e.what());
  } catch (...) {
    return "error: unknown failure";
  }
}

}  // namespace prt
