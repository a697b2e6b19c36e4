// A fault injector for the CLI tests, loaded with LD_PRELOAD: write() to a file whose path
// contains $TORSION_FAIL_WRITES_TO fails with ENOSPC ("No space left on device") once
// $TORSION_FAIL_WRITES_AFTER bytes (default 0) have gone to such files, as on a full disk.
// It proves it was loaded by creating $TORSION_FAIL_WRITES_MARK, so a test can tell "the
// program ignored the failure" from "the shim could not be preloaded".
#include <dlfcn.h>
#include <fcntl.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>  // before dlfcn.h, which needs size_t
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

using WriteFunction = ssize_t (*)(int, const void*, size_t);

long long written_to_target = 0;

__attribute__((constructor)) void markLoaded() {
  const char* mark = getenv("TORSION_FAIL_WRITES_MARK");
  if (mark != nullptr) {
    int fd = open(mark, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) close(fd);
  }
}

bool isTarget(int fd) {
  const char* target = getenv("TORSION_FAIL_WRITES_TO");
  if (target == nullptr || *target == '\0') return false;
  char link[64], path[4096];
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  ssize_t n = readlink(link, path, sizeof path - 1);
  if (n <= 0) return false;
  path[n] = '\0';
  return std::strstr(path, target) != nullptr;
}

}  // namespace

extern "C" ssize_t write(int fd, const void* data, size_t size) {
  static auto real_write = reinterpret_cast<WriteFunction>(dlsym(RTLD_NEXT, "write"));
  if (fd > 2 && isTarget(fd)) {
    const char* after = getenv("TORSION_FAIL_WRITES_AFTER");
    const long long limit = after != nullptr ? std::atoll(after) : 0;
    if (written_to_target + static_cast<long long>(size) > limit) {
      errno = ENOSPC;
      return -1;
    }
    written_to_target += static_cast<long long>(size);
  }
  return real_write(fd, data, size);
}
