#include "prt/error.hpp"

#include <filesystem>
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

std::string elide(const std::string& value, std::size_t limit) {
  if (value.size() <= limit || limit < 16) return value;
  const std::size_t head = limit * 2 / 3, tail = limit - head;
  return value.substr(0, head) + "...[" + std::to_string(value.size() - head - tail) +
         " characters elided]..." + value.substr(value.size() - tail);
}

std::string Error::bounded(const std::string& message) {
  return elide(message, kMaxMessage);
}

std::string filesystem_message(const std::filesystem::filesystem_error& e) {
  // what() is "filesystem error: cannot create directories: No space left on
  // device [path]": the path moves to the front, as every other message has it.
  std::string text = e.what();
  const std::string prefix = "filesystem error: ";
  if (text.rfind(prefix, 0) == 0) text = text.substr(prefix.size());
  const std::string path = e.path1().string();
  if (!path.empty()) {
    const auto bracket = text.find(" [" + path + "]");
    if (bracket != std::string::npos) text = text.substr(0, bracket);
    return path + ": " + text;
  }
  return text;
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
  } catch (const std::filesystem::filesystem_error& e) {
    return error_line(filesystem_message(e));
  } catch (const std::exception& e) {
    return error_line(e.what());
  } catch (...) {
    return "error: unknown failure";
  }
}

}  // namespace prt
