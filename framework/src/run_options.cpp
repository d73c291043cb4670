// How a run reports (progress, messages) and the stage timings it collects.
#include "prt/run_options.hpp"

#include <algorithm>
#include <cstdio>

#include "prt/log.hpp"
#include "prt/memory.hpp"

namespace prt {

std::string StageTimes::table() const {
  std::string out;
  double total = 0;
  char line[160];
  for (const auto& [name, seconds] : stages) {
    std::snprintf(line, sizeof line, "  %-28s %9.3f s\n", name.c_str(), seconds);
    out += line;
    total += seconds;
  }
  std::snprintf(line, sizeof line, "  %-28s %9.3f s\n", "total", total);
  return out + line;
}

void RunOptions::message(const std::string& text) const {
  if (log)
    log(text);
  else if (!quiet)
    log_info(text);
}

void RunOptions::warn(const std::string& text) const {
  if (log)
    log("warning: " + text);
  else
    log_warning(text);
}

double RunOptions::budget() const {
  return memory_budget > 0 ? memory_budget : kDefaultMemoryFraction * physical_memory();
}

}  // namespace prt
