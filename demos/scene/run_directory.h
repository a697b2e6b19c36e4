#pragma once
// The --out directory of a run, kept so that one run's files never mix with another's
// (docs/outputs.md):
//   1. summary.json is replaced first, saying "completed": false and listing the run's outputs;
//   2. the files of the earlier run (the "outputs" of its summary.json) and this run's own names
//      are removed, and so are the temporaries a killed run left of those names;
//   3. the CSVs grow row by row under their own names (whole rows only);
//   4. at the end the meshes and haptic logs are written whole, and summary.json is replaced by
//      the final one.
// A reader who finds "completed": false knows the other files are partial or absent.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "torsion/device/file_io.h"
#include "torsion/result.h"

namespace torsion::scene {

class RunDirectory {
 public:
  /// Creates the directory if needed, writes the first summary (which should say
  /// "completed": false) and removes stale files. `outputs`: the names this run will write
  /// besides summary.json. Errors name the file and the reason.
  static Result<RunDirectory> prepare(const std::string& directory,
                                      const std::vector<std::string>& outputs,
                                      nlohmann::json first_summary);

  /// "<directory>/<name>".
  std::string path(const std::string& name) const;
  /// Replaces summary.json (temporary, flush, rename). Names are kept valid UTF-8 (invalid bytes
  /// become U+FFFD) so a scene file name in any encoding cannot stop the summary.
  Status writeSummary(const nlohmann::json& summary) const;
  const std::string& directory() const { return directory_; }

 private:
  explicit RunDirectory(std::string directory) : directory_(std::move(directory)) {}
  std::string directory_;
};

/// An open CSV of the run: rows are written whole (device::RowFile); errors name the file.
class CsvOutput {
 public:
  Status open(const std::string& path, const std::string& header);
  Status row(const std::string& text);
  Status close();
  bool isOpen() const { return file_.isOpen(); }

 private:
  device::RowFile file_;
};

}  // namespace torsion::scene
