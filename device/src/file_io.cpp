#include "torsion/device/file_io.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>

namespace torsion::device {

namespace {

std::atomic<std::size_t> g_max_input_bytes{kDefaultMaxInputFileBytes};

std::string reason(int error) {
  return std::strerror(error);
}

std::string fileKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a file";
}

// Writes all of `data`, retrying short writes and EINTR; errno is left set on failure.
bool writeAll(int fd, std::string_view data) {
  const char* p = data.data();
  std::size_t left = data.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  return true;
}

std::string temporaryBeside(const std::string& path) {
  return path + ".tmp-" + std::to_string(::getpid());
}

// Writes `text` to a new temporary beside `path` and flushes it to disk; the temporary's name on
// success, an error naming `path` otherwise (and no temporary left).
std::string writeTemporary(const std::string& path, std::string_view text, std::string& temp) {
  if (std::string refused = refuseUnlessRegularOrAbsent(path); !refused.empty()) return refused;
  temp = temporaryBeside(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return path + ": cannot write: " + reason(errno);
  if (!writeAll(fd, text) || ::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    return path + ": cannot write: " + reason(error);
  }
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(temp.c_str());
    return path + ": cannot write: " + reason(error);
  }
  return {};
}

}  // namespace

// A rename replaces whatever holds the name: a device node, a FIFO or a symbolic link would
// become a regular file (as root, "/dev/full" would stop being the device). So every write checks
// here, the atomic ones before their temporary is written and again just before the rename.
// lstat: a symbolic link is refused itself, not judged by what it points to.
std::string refuseUnlessRegularOrAbsent(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return {};  // nothing there (or unreachable: open says)
  if (S_ISREG(st.st_mode)) return {};
  return path + ": cannot write: is " + fileKind(st.st_mode) + ", not a regular file";
}

std::size_t maxInputFileBytes() {
  return g_max_input_bytes.load();
}

void setMaxInputFileBytes(std::size_t bytes) {
  g_max_input_bytes.store(bytes);
}

std::string readRegularFile(const std::string& path, std::string& text) {
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever before fstat.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return path + ": cannot open: " + reason(errno);
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int error = errno;
    ::close(fd);
    return path + ": cannot open: " + reason(error);
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return path + ": cannot open: is " + fileKind(st.st_mode) + ", not a regular file";
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  const std::size_t cap = maxInputFileBytes();
  if (size > cap) {
    ::close(fd);
    return path + ": " + std::to_string(size) + " bytes, above the input size cap of " +
           std::to_string(cap) + " bytes (raise it with --max-input-mb)";
  }
  text.assign(size, '\0');
  std::size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(fd, text.data() + got, size - got);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      const int error = errno;
      ::close(fd);
      return path + ": read failed: " + reason(error);
    }
    if (n == 0) break;  // the file shrank while we read it
    got += static_cast<std::size_t>(n);
  }
  text.resize(got);
  ::close(fd);
  return {};
}

std::string writeFileAtomically(const std::string& path, std::string_view text) {
  std::string temp;
  if (std::string error = writeTemporary(path, text, temp); !error.empty()) return error;
  if (std::string refused = refuseUnlessRegularOrAbsent(path); !refused.empty()) {
    ::unlink(temp.c_str());
    return refused;
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(temp.c_str());
    return path + ": cannot write: " + reason(error);
  }
  return {};
}

std::string writeFilesTogether(const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::string> temps;
  auto discard = [&temps] {
    for (const std::string& t : temps)
      ::unlink(t.c_str());
  };
  for (const auto& [path, text] : files) {
    std::string temp;
    if (std::string error = writeTemporary(path, text, temp); !error.empty()) {
      discard();
      return error;
    }
    temps.push_back(temp);
  }
  // Keep each replaced file under a backup name until all renames have succeeded.
  std::vector<std::string> backups(files.size());
  std::size_t replaced = 0;
  std::string failure;
  for (; replaced < files.size(); ++replaced) {
    const std::string& path = files[replaced].first;
    const std::string backup = path + ".old-" + std::to_string(::getpid());
    if (std::string refused = refuseUnlessRegularOrAbsent(path); !refused.empty()) {
      failure = refused;
      break;
    }
    if (::link(path.c_str(), backup.c_str()) == 0) {
      backups[replaced] = backup;
    } else if (errno != ENOENT) {
      // No hard links here (some file systems): move the old file aside instead.
      if (::rename(path.c_str(), backup.c_str()) != 0) {
        failure = path + ": cannot write: " + reason(errno);
        break;
      }
      backups[replaced] = backup;
    }
    if (::rename(temps[replaced].c_str(), path.c_str()) != 0) {
      failure = path + ": cannot write: " + reason(errno);
      if (!backups[replaced].empty()) {
        // Put the old file back if it was moved aside; drop the link if it was linked.
        if (::access(path.c_str(), F_OK) != 0) {
          ::rename(backups[replaced].c_str(), path.c_str());
        } else {
          ::unlink(backups[replaced].c_str());
        }
      }
      break;
    }
  }
  if (failure.empty()) {
    for (const std::string& b : backups)
      if (!b.empty()) ::unlink(b.c_str());
    return {};
  }
  // Roll back: the files already renamed get their old content (or vanish if they were new).
  for (std::size_t k = 0; k < replaced; ++k) {
    const std::string& path = files[k].first;
    if (!backups[k].empty()) {
      ::rename(backups[k].c_str(), path.c_str());
    } else {
      ::unlink(path.c_str());
    }
  }
  for (std::size_t k = replaced; k < temps.size(); ++k)
    ::unlink(temps[k].c_str());
  return failure;
}

std::string removeStaleTemporaries(const std::string& directory,
                                   const std::function<bool(const std::string&)>& ours) {
  DIR* dir = ::opendir(directory.c_str());
  if (dir == nullptr) return errno == ENOENT ? std::string() : directory + ": " + reason(errno);
  std::string failure;
  while (const dirent* entry = ::readdir(dir)) {
    const std::string name = entry->d_name;
    // "<name>.tmp-<pid>" (temporaryBeside) or "<name>.old-<pid>" (writeFilesTogether's backup).
    const size_t dash = name.rfind('-');
    if (dash == std::string::npos || dash < 4 || dash + 1 == name.size() || dash + 10 < name.size())
      continue;
    const std::string tag = name.substr(dash - 4, 5);
    if (tag != ".tmp-" && tag != ".old-") continue;
    const std::string digits = name.substr(dash + 1);
    if (digits.find_first_not_of("0123456789") != std::string::npos) continue;
    if (!ours(name.substr(0, dash - 4))) continue;
    const long pid = std::stol(digits);
    // Alive (or not ours to signal: EPERM) means it may still be writing: keep it.
    if (pid == ::getpid() || pid <= 0 || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
      continue;
    std::string path = directory;
    path += '/';
    path += name;
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    if (::unlink(path.c_str()) != 0 && errno != ENOENT && failure.empty())
      failure = path + ": cannot remove a stale temporary: " + reason(errno);
  }
  ::closedir(dir);
  return failure;
}

RowFile::RowFile(RowFile&& other) noexcept : fd_(other.fd_), path_(std::move(other.path_)) {
  other.fd_ = -1;
}

RowFile& RowFile::operator=(RowFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    path_ = std::move(other.path_);
    other.fd_ = -1;
  }
  return *this;
}

RowFile::~RowFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::string RowFile::open(const std::string& path) {
  if (fd_ >= 0) ::close(fd_);
  path_ = path;
  if (std::string refused = refuseUnlessRegularOrAbsent(path); !refused.empty()) return refused;
  // O_NOFOLLOW: a symbolic link put there after the check is not followed either.
  fd_ =
      ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0) return path + ": cannot write: " + reason(errno);
  return {};
}

std::string RowFile::write(std::string_view row) {
  if (fd_ < 0) return path_ + ": cannot write: not open";
  if (!writeAll(fd_, row)) return path_ + ": write failed: " + reason(errno);
  return {};
}

std::string RowFile::close() {
  if (fd_ < 0) return {};
  const int fd = fd_;
  fd_ = -1;
  if (::fsync(fd) != 0 && errno != EINVAL) {
    const int error = errno;
    ::close(fd);
    return path_ + ": write failed: " + reason(error);
  }
  if (::close(fd) != 0) return path_ + ": write failed: " + reason(errno);
  return {};
}

}  // namespace torsion::device
