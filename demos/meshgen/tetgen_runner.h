#pragma once
// Running Debian's `tetgen` program (TetGen 1.5 is AGPL: we run the program and read its files,
// we never link it). The input is written into a temporary directory, tetgen writes its .node/.ele
// beside it, and its output is captured for error messages.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "torsion/result.h"

namespace torsion::meshgen {

/// A fresh directory under the system temp directory, removed with its contents on destruction.
class TempDir {
 public:
  static Result<TempDir> create(std::string_view prefix);
  TempDir(TempDir&& other) noexcept;
  TempDir& operator=(TempDir&& other) noexcept;
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir();

  const std::filesystem::path& path() const { return path_; }

 private:
  explicit TempDir(std::filesystem::path path) : path_(std::move(path)) {}
  std::filesystem::path path_;
};

/// The first executable file `name` in the directories of $PATH, or an empty path.
std::filesystem::path findOnPath(std::string_view name);

/// The tetgen program, or the error "torsion mesh <command>: needs the 'tetgen' command (Debian
/// package 'tetgen'); it is not on PATH".
Result<std::filesystem::path> findTetgen(std::string_view command);

/// How a program run by runProcess ended, and what it printed.
struct ProcessResult {
  bool exited = false;
  int exit_code = 0;
  int signal = 0;
  std::string out;
  std::string err;
};

/// Runs argv[0] (a path) with stdin from /dev/null and stdout/stderr into files in `dir`.
Result<ProcessResult> runProcess(const std::vector<std::string>& argv,
                                 const std::filesystem::path& dir);

/// What one tetgen run left behind.
struct TetgenRun {
  std::filesystem::path node;  ///< <input stem>.1.node
  std::filesystem::path ele;   ///< <input stem>.1.ele
  int tets = 0;                ///< from the .ele header
};

/// Runs `tetgen <switches> <input>` with stdout and stderr captured in files beside the input.
/// Fails with a message naming the input, how tetgen ended and the tail of what it printed; when
/// it printed nothing useful (TetGen 1.5 aborts without a message on many faults), says so.
Result<TetgenRun> runTetgen(const std::filesystem::path& tetgen, const std::string& switches,
                            const std::filesystem::path& input);

/// Runs `tetgen -d` (self-intersection check) on a PLC. Returns the pairs of facets (0-based, in
/// input order) that tetgen reports intersecting; an empty list when it found none.
Result<std::vector<std::pair<int, int>>> findSelfIntersections(const std::filesystem::path& tetgen,
                                                               const std::filesystem::path& input);

}  // namespace torsion::meshgen
