#include "prt/log.hpp"

#include <cstdio>
#include <mutex>
#include <set>

namespace prt {

namespace {
std::mutex sink_mutex;
LogSink sink;  // null: standard output and error
}  // namespace

void set_log_sink(LogSink new_sink) {
  std::lock_guard lock(sink_mutex);
  sink = std::move(new_sink);
}

namespace {
void emit(LogLevel level, const std::string& text) {
  LogSink current;
  {
    std::lock_guard lock(sink_mutex);
    current = sink;
  }
  if (current) {  // outside the lock: a sink may log or set another sink
    current(level, text);
  } else if (level == LogLevel::warning) {
    std::fprintf(stderr, "prt: warning: %s\n", text.c_str());
  } else {
    std::printf("%s\n", text.c_str());
    std::fflush(stdout);
  }
}
}  // namespace

void log_info(const std::string& text) {
  emit(LogLevel::info, text);
}

void log_warning(const std::string& text) {
  emit(LogLevel::warning, text);
}

void log_warning_once(const std::string& text) {
  static std::mutex mutex;
  static std::set<std::string> said;
  {
    std::lock_guard lock(mutex);
    if (!said.insert(text).second) return;
  }
  emit(LogLevel::warning, text);
}

}  // namespace prt
