#include "run_directory.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

namespace torsion::scene {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSummary = "summary.json";

// A name an earlier summary may list that is safe to remove: one plain entry of this directory.
bool plainFileName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name != kSummary;
}

// The outputs listed by the summary.json already in the directory, if any can be read.
std::vector<std::string> earlierOutputs(const std::string& summary_path) {
  std::string text;
  if (!device::readRegularFile(summary_path, text).empty()) return {};
  const nlohmann::json earlier = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  std::vector<std::string> names;
  if (!earlier.is_object() || !earlier.contains("outputs") || !earlier["outputs"].is_array())
    return names;
  for (const nlohmann::json& n : earlier["outputs"])
    if (n.is_string()) names.push_back(n.get<std::string>());
  return names;
}

}  // namespace

Result<RunDirectory> RunDirectory::prepare(const std::string& directory,
                                           const std::vector<std::string>& outputs,
                                           nlohmann::json first_summary) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return Error{directory + ": cannot create the output directory: " + ec.message()};
  RunDirectory dir(directory);

  std::set<std::string> stale(outputs.begin(), outputs.end());
  for (const std::string& name : earlierOutputs(dir.path(kSummary)))
    stale.insert(name);

  first_summary["outputs"] = outputs;
  if (Status written = dir.writeSummary(first_summary); !written) return written.error();

  // Only regular files are removed: a FIFO, a device or a link at one of this run's names is an
  // error (nothing would be written over it), at an earlier run's name it is left alone.
  const std::set<std::string> ours(outputs.begin(), outputs.end());
  for (const std::string& name : stale) {
    if (!plainFileName(name)) continue;
    const std::string path = dir.path(name);
    if (std::string refused = device::refuseUnlessRegularOrAbsent(path); !refused.empty()) {
      if (ours.count(name) != 0) return Error{refused};
      continue;
    }
    if (::unlink(path.c_str()) != 0 && errno != ENOENT)
      return Error{path + ": cannot remove the earlier run's file: " + std::strerror(errno)};
  }
  // A killed run leaves the temporaries of its atomic writes ("<name>.tmp-<pid>"): those of
  // these names, summary.json's included, whose process is gone.
  stale.insert(kSummary);
  const std::string left = device::removeStaleTemporaries(
      directory, [&stale](const std::string& name) { return stale.count(name) != 0; });
  if (!left.empty()) return Error{left};
  return dir;
}

std::string RunDirectory::path(const std::string& name) const {
  return (fs::path(directory_) / name).string();
}

Status RunDirectory::writeSummary(const nlohmann::json& summary) const {
  const std::string text =
      summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  if (std::string error = device::writeFileAtomically(path(kSummary), text); !error.empty())
    return Error{error};
  return Ok{};
}

Status CsvOutput::open(const std::string& path, const std::string& header) {
  if (std::string error = file_.open(path); !error.empty()) return Error{error};
  return row(header);
}

Status CsvOutput::row(const std::string& text) {
  if (std::string error = file_.write(text); !error.empty()) return Error{error};
  return Ok{};
}

Status CsvOutput::close() {
  if (std::string error = file_.close(); !error.empty()) return Error{error};
  return Ok{};
}

}  // namespace torsion::scene
