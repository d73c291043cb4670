/* A full disk on demand, for tests: LD_PRELOAD this library and set
 * PRT_FAULT_BYTES=N; writes to regular files succeed until N bytes in all
 * have been written, then write as much as is left and fail with ENOSPC, as
 * a file system that fills up does. Standard streams, pipes and sockets are
 * not counted. Used where the test cannot mount a small tmpfs. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

static atomic_llong left = -1; /* -1: not read yet */

static long long budget(void) {
  long long value = atomic_load(&left);
  if (value == -1) {
    const char* text = getenv("PRT_FAULT_BYTES");
    value = text ? atoll(text) : (long long)1 << 62;
    long long expected = -1;
    atomic_compare_exchange_strong(&left, &expected, value);
    value = atomic_load(&left);
  }
  return value;
}

static int counted(int fd) {
  struct stat s;
  return fd > 2 && fstat(fd, &s) == 0 && S_ISREG(s.st_mode);
}

/* How many of `size` bytes may be written now; 0 with errno set when none. */
static size_t allow(int fd, size_t size) {
  if (!counted(fd) || size == 0) return size;
  for (;;) {
    long long now = budget();
    if (now <= 0) {
      errno = ENOSPC;
      return 0;
    }
    const long long take = (long long)size < now ? (long long)size : now;
    if (atomic_compare_exchange_strong(&left, &now, now - take)) return (size_t)take;
  }
}

#define REAL(name) ((__typeof__(&name))dlsym(RTLD_NEXT, #name))

ssize_t write(int fd, const void* data, size_t size) {
  const size_t n = allow(fd, size);
  if (size > 0 && n == 0) return -1;
  return REAL(write)(fd, data, n);
}

ssize_t pwrite(int fd, const void* data, size_t size, off_t at) {
  const size_t n = allow(fd, size);
  if (size > 0 && n == 0) return -1;
  return REAL(pwrite)(fd, data, n, at);
}

ssize_t pwrite64(int fd, const void* data, size_t size, off_t at) {
  const size_t n = allow(fd, size);
  if (size > 0 && n == 0) return -1;
  return REAL(pwrite64)(fd, data, n, at);
}

ssize_t writev(int fd, const struct iovec* v, int count) {
  size_t size = 0;
  for (int i = 0; i < count; ++i) size += v[i].iov_len;
  const size_t n = allow(fd, size);
  if (size > 0 && n == 0) return -1;
  if (n == size) return REAL(writev)(fd, v, count);
  return REAL(write)(fd, v[0].iov_base, n < v[0].iov_len ? n : v[0].iov_len);
}

int posix_fallocate(int fd, off_t at, off_t size) {
  if (counted(fd) && budget() < (long long)size) return ENOSPC;
  return REAL(posix_fallocate)(fd, at, size);
}

int fallocate(int fd, int mode, off_t at, off_t size) {
  if (counted(fd) && budget() < (long long)size) {
    errno = ENOSPC;
    return -1;
  }
  return REAL(fallocate)(fd, mode, at, size);
}
