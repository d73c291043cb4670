#include "prt/error.hpp"

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

}  // namespace prt
