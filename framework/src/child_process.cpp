#include "child_process.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
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
