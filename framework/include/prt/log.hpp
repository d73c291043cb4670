// Where the library's messages go: one sink for the process, set by the app
// (a GUI, the Python bindings, a test), like Progress::set_sink. The library
// never prints on its own.
#pragma once
#include <functional>
#include <string>

namespace prt {

enum class LogLevel { info, warning };
using LogSink = std::function<void(LogLevel level, const std::string& text)>;

// null (the default): info lines to standard output, warnings as
// "prt: warning: ..." to standard error.
void set_log_sink(LogSink sink);
void log_info(const std::string& text);
void log_warning(const std::string& text);
// The same warning once per process (a plan made twice, a metric asked for
// by every render of a session).
void log_warning_once(const std::string& text);

}  // namespace prt
