#include "prt/memory.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace prt {

namespace {

// Address space this process may still map under RLIMIT_AS (infinite when unlimited).
double address_space_left() {
  struct rlimit limit {};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return 1e300;
  std::ifstream status("/proc/self/statm");
  double pages = 0;
  status >> pages;
  return std::max(0.0, double(limit.rlim_cur) - pages * double(sysconf(_SC_PAGESIZE)));
}

}  // namespace

double available_memory() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kilobytes = 0, bytes = -1;
  while (meminfo >> key >> kilobytes) {
    if (key == "MemAvailable:") {
      bytes = kilobytes * 1024.0;
      break;
    }
    meminfo.ignore(256, '\n');
  }
  if (bytes < 0) bytes = double(sysconf(_SC_AVPHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  return std::min(bytes, address_space_left());
}

double physical_memory() {
  double bytes = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  for (const char* limit : {"/sys/fs/cgroup/memory.max",                       // cgroup v2
                            "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {  // v1
    std::ifstream in(limit);
    double value = 0;
    if (in >> value && value > 0) bytes = std::min(bytes, value);  // "max" reads as nothing
  }
  return bytes;
}

std::string gigabytes(double bytes) {
  char text[32];
  if (bytes < 1e9)
    std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
  else
    std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  return text;
}

double peak_resident_bytes() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) * 1024.0;  // kilobytes on Linux
}

}  // namespace prt
