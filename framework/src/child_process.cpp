#include "child_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>

#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {

namespace {

int verdict_pipe = -1;  // the child's write end, while a child runs its work

std::string read_all(int fd) {
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return text;
    text.append(buffer, static_cast<std::size_t>(n));
  }
}

}  // namespace

bool in_child_process() {
  return verdict_pipe >= 0;
}

void fail_child_process(const std::string& message) {
  if (verdict_pipe < 0) throw Error(message);  // ran in this process: an ordinary error
  const std::string text = message.empty() ? "failed" : message;
  write_fully(verdict_pipe, text.data(), text.size());  // the parent reports a lost message
  ::_exit(1);
}

void run_in_child_process(const std::string& what, const std::function<void()>& work) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return work();
  std::cout.flush();
  std::cerr.flush();
  const pid_t child = ::fork();
  if (child < 0) {  // no memory for a child: the work runs here
    ::close(ends[0]), ::close(ends[1]);
    return work();
  }
  if (child == 0) {
    ::close(ends[0]);
    verdict_pipe = ends[1];
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives the process it works for
    // Libraries print their failures to std::cerr (HDF5's C++ destructors):
    // the verdict carries the one message that matters.
    std::cerr.setstate(std::ios::badbit);
    try {
      work();
    } catch (const std::exception& e) {
      fail_child_process(e.what());
    } catch (...) {
      fail_child_process(what + ": failed");
    }
    ::_exit(0);  // no atexit handlers: a library's cleanup is the parent's
  }
  ::close(ends[1]);
  const std::string message = read_all(ends[0]);
  ::close(ends[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  if (!message.empty()) throw Error(message);
  if (WIFSIGNALED(status))
    throw Error(what + ": the process doing it was killed by signal " +
                std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) +
                "); nothing was kept");
  throw Error(what + ": failed");
}

}  // namespace prt

namespace prt {

namespace {

double mapped_bytes_now() {
  std::FILE* statm = std::fopen("/proc/self/statm", "r");
  unsigned long pages = 0;
  if (statm) {
    if (std::fscanf(statm, "%lu", &pages) != 1) pages = 0;
    std::fclose(statm);
  }
  return double(pages) * double(::sysconf(_SC_PAGESIZE));
}

// The default action for `signal`, set with the system call itself: a
// sanitizer intercepts signal() and sigaction() and keeps its own handler,
// which in a forked child may spin instead of ending it.
void default_action(int signal) {
  struct {
    void* handler = nullptr;  // SIG_DFL
    unsigned long flags = 0;
    void* restorer = nullptr;
    unsigned long mask = 0;
  } action;
  ::syscall(SYS_rt_sigaction, signal, &action, nullptr, sizeof action.mask);
}

// `grace` past the soft limit, the hard one (processor time: SIGXCPU at the
// soft limit, SIGKILL at the hard one).
void set_limit(int resource, double value, double grace = 0) {
  const rlimit limits{static_cast<rlim_t>(value), static_cast<rlim_t>(value + grace)};
  ::setrlimit(resource, &limits);
}

std::string how_it_ended(const std::string& what, int status, const ChildLimits& limits) {
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    if (signal == SIGXCPU)
      return what + ": parsing it took more than " + std::to_string(int(limits.cpu_seconds)) +
             " s of processor time and was stopped (a damaged or crafted file); nothing was read";
    return what + ": the process parsing it was killed by signal " + std::to_string(signal) + " (" +
           ::strsignal(signal) + "), a defect of the HDF5 library met by a damaged or " +
           "crafted file; nothing was read";
  }
  return what + ": the process parsing it failed (exit status " +
         std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + "); nothing was read";
}

int wait_for(pid_t child) {
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

void read_from_child(int fd, void* data, std::size_t size, double idle_seconds) {
  auto* at = static_cast<char*>(data);
  while (size > 0) {
    if (idle_seconds > 0) {
      pollfd ready{fd, POLLIN, 0};
      const int n = ::poll(&ready, 1, int(std::min(idle_seconds, 1e6) * 1000));
      if (n < 0 && errno == EINTR) continue;
      if (n == 0) throw ChildSilent();
    }
    const ssize_t n = ::read(fd, at, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw ChildStreamEnded();
    at += n, size -= std::size_t(n);
  }
}

namespace {

// The child's side: its own signal actions, quiet output and limits, then
// `produce`; it ends without unwinding (a library's cleanup is the parent's).
[[noreturn]] void run_child(int fd, const ChildLimits& limits, double mapped,
                            const std::function<void(int)>& produce) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  // This process's handlers (removing its temporaries, a test framework's
  // or a sanitizer's reports) are not the child's: it just ends.
  for (int signal : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGXCPU, SIGINT, SIGTERM})
    default_action(signal);
  std::cerr.setstate(std::ios::badbit);
  // A library's own prints (libhdf5's diagnostics) go nowhere: the stream
  // carries the one message that matters, and a log file must not grow.
  const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null >= 0) ::dup2(null, STDOUT_FILENO), ::dup2(null, STDERR_FILENO), ::close(null);
  set_limit(RLIMIT_CORE, 0);
  set_limit(RLIMIT_FSIZE, 0);
  if (limits.memory_bytes > 0) set_limit(RLIMIT_AS, mapped + limits.memory_bytes);
  if (limits.cpu_seconds > 0) set_limit(RLIMIT_CPU, std::ceil(limits.cpu_seconds), 1);
  try {
    produce(fd);
  } catch (...) {
    ::_exit(1);
  }
  ::_exit(0);
}

}  // namespace

void exchange_with_child(const std::string& what, const ChildLimits& limits,
                         const std::function<void(int)>& produce,
                         const std::function<void(int)>& consume) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw Error(what + ": cannot start a process to parse it (" + std::strerror(errno) + ")");
  std::cout.flush();
  std::cerr.flush();
  const double mapped = mapped_bytes_now();
  const pid_t child = ::fork();
  if (child < 0) {
    const int error = errno;
    ::close(ends[0]), ::close(ends[1]);
    throw Error(what + ": cannot start a process to parse it (" + std::strerror(error) + ")");
  }
  if (child == 0) {
    ::close(ends[0]);
    run_child(ends[1], limits, mapped, produce);
  }
  ::close(ends[1]);
  try {
    consume(ends[0]);
  } catch (const ChildStreamEnded&) {
    ::close(ends[0]);
    throw Error(how_it_ended(what, wait_for(child), limits));
  } catch (const ChildSilent&) {
    ::kill(child, SIGKILL);
    ::close(ends[0]);
    wait_for(child);
    throw Error(what + ": the process parsing it sent nothing for " +
                std::to_string(int(limits.idle_seconds)) +
                " s and was stopped (a damaged or crafted file); nothing was read");
  } catch (...) {
    ::kill(child, SIGKILL);
    ::close(ends[0]);
    wait_for(child);
    throw;
  }
  ::close(ends[0]);
  const int status = wait_for(child);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(how_it_ended(what, status, limits));
}

}  // namespace prt
