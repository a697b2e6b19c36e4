#pragma once
// Files that are complete or absent, and input that is a bounded regular file. Shared by every
// reader and writer of the project (the device layer is the lowest one; it depends on nothing).
//
// Writing: a whole file goes to a temporary beside it ("<name>.tmp-<pid>"), is flushed to disk,
// then renamed over the name, so a reader sees the old file or the new one, never a torn one; on
// any failure the temporary is removed and the old file is left as it was. Only a regular file (or
// nothing) is replaced: a rename would turn a device node, a FIFO, a socket or a symbolic link into
// a regular file, so those (and directories) are refused with their kind named. A file that grows
// row by row (RowFile) is written in whole rows, one write() each, so a killed process leaves only
// whole rows behind.
//
// Reading: only regular files are read (a FIFO would block forever, /dev/zero never ends), and
// only up to a size cap (maxInputFileBytes, raised by the CLI's --max-input-mb).
//
// Every error is a message naming the file and the system's reason (strerror); empty is success.

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace torsion::device {

/// The default cap on one input file: 1 GiB (the largest shipped mesh is a few MB).
inline constexpr std::size_t kDefaultMaxInputFileBytes = std::size_t{1} << 30;

/// The process-wide cap on input files (bytes). Set once at start-up, before any reading thread.
std::size_t maxInputFileBytes();
void setMaxInputFileBytes(std::size_t bytes);

/// Reads a whole regular file into `text`. Errors: "<path>: cannot open: <reason>",
/// "<path>: cannot open: is a FIFO, not a regular file", "<path>: 2147483648 bytes, above the input
/// size cap of 1073741824 bytes (raise it with --max-input-mb)", "<path>: read failed: <reason>".
std::string readRegularFile(const std::string& path, std::string& text);

/// Empty when `path` holds a regular file or nothing, the only things a write may replace;
/// otherwise "<path>: cannot write: is a FIFO, not a regular file" (or a character device, a block
/// device, a socket, a directory, a symbolic link). Every writer here checks with it.
std::string refuseUnlessRegularOrAbsent(const std::string& path);

/// Replaces `path` by `text` (temporary, fsync, rename). Errors: "<path>: cannot write: <reason>",
/// "<path>: cannot write: is a FIFO, not a regular file" (a device, socket, directory or symbolic
/// link likewise: nothing is written and what is there stays).
std::string writeFileAtomically(const std::string& path, std::string_view text);

/// Replaces several files together or none of them (e.g. a TetGen .node/.ele pair): all are
/// written to temporaries first, then renamed; a failed rename puts back the files already
/// replaced. Each name must hold a regular file or nothing, as for writeFileAtomically.
std::string writeFilesTogether(const std::vector<std::pair<std::string, std::string>>& files);

/// Removes from `directory` the temporaries that atomic writes left when their process was killed
/// (SIGKILL, a power cut): entries "<name>.tmp-<pid>" and "<name>.old-<pid>" whose process no
/// longer runs, for the names `ours` accepts. Nothing else is touched: not another program's
/// files, not a temporary of a process still running. An error names the entry that could not be
/// removed.
std::string removeStaleTemporaries(const std::string& directory,
                                   const std::function<bool(const std::string&)>& ours);

/// A file written row by row under its final name: each row goes out whole in one write() (no
/// user-space buffer), so after a crash or SIGKILL the file holds whole rows only.
class RowFile {
 public:
  RowFile() = default;
  RowFile(const RowFile&) = delete;
  RowFile& operator=(const RowFile&) = delete;
  RowFile(RowFile&& other) noexcept;
  RowFile& operator=(RowFile&& other) noexcept;
  ~RowFile();  ///< closes without reporting; call close() to learn of a failure

  /// Creates (truncates) the file; only a regular file or nothing may be at `path`
  /// (refuseUnlessRegularOrAbsent). Error: "<path>: cannot write: <reason>".
  std::string open(const std::string& path);
  bool isOpen() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  /// Writes the row (which should end in '\n') completely, retrying short writes.
  std::string write(std::string_view row);
  /// Flushes to disk and closes; an error names the file.
  std::string close();

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace torsion::device
