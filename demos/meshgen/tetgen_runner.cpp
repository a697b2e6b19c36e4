#include "tetgen_runner.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <regex>
#include <sstream>

#include "torsion/mesh/mesh_io.h"

extern char** environ;  // NOLINT: POSIX

namespace torsion::meshgen {

namespace fs = std::filesystem;

// ---- TempDir ----

Result<TempDir> TempDir::create(std::string_view prefix) {
  std::error_code ec;
  fs::path base = fs::temp_directory_path(ec);
  if (ec) base = "/tmp";
  std::string pattern = (base / (std::string(prefix) + "-XXXXXX")).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (::mkdtemp(buffer.data()) == nullptr) {
    return Error{"cannot create a temporary directory under " + base.string() + ": " +
                 std::strerror(errno)};
  }
  return TempDir(fs::path(buffer.data()));
}

TempDir::TempDir(TempDir&& other) noexcept : path_(std::move(other.path_)) {
  other.path_.clear();
}

TempDir& TempDir::operator=(TempDir&& other) noexcept {
  if (this != &other) {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
    path_ = std::move(other.path_);
    other.path_.clear();
  }
  return *this;
}

TempDir::~TempDir() {
  if (path_.empty()) return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

// ---- Finding and running programs ----

fs::path findOnPath(std::string_view name) {
  const char* path_env = std::getenv("PATH");
  if (path_env == nullptr) return {};
  std::string_view dirs(path_env);
  while (true) {
    const size_t colon = dirs.find(':');
    std::string_view dir = dirs.substr(0, colon);
    if (dir.empty()) dir = ".";
    const fs::path candidate = fs::path(std::string(dir)) / std::string(name);
    struct stat st {};
    if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
        ::access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
    if (colon == std::string_view::npos) break;
    dirs.remove_prefix(colon + 1);
  }
  return {};
}

Result<fs::path> findTetgen(std::string_view command) {
  fs::path tetgen = findOnPath("tetgen");
  if (tetgen.empty()) {
    return Error{"torsion mesh " + std::string(command) +
                 ": needs the 'tetgen' command (Debian package 'tetgen'); it is not on PATH"};
  }
  return tetgen;
}

namespace {

std::string slurp(const fs::path& path) {
  Result<std::string> text = readTextFile(path);
  return text ? std::move(text).value() : std::string();
}

}  // namespace

Result<ProcessResult> runProcess(const std::vector<std::string>& argv, const fs::path& dir) {
  const fs::path out_path = dir / "tetgen.stdout";
  const fs::path err_path = dir / "tetgen.stderr";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  std::vector<char*> args;
  for (const std::string& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));  // NOLINT
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return Error{"cannot run " + argv[0] + ": " + std::strerror(spawned)};
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return Error{"waiting for " + argv[0] + ": " + std::strerror(errno)};
  }
  ProcessResult result;
  result.exited = WIFEXITED(status);
  result.exit_code = result.exited ? WEXITSTATUS(status) : 0;
  result.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  result.out = slurp(out_path);
  result.err = slurp(err_path);
  return result;
}

namespace {

// TetGen buffers stdout and aborts (uncaught exception) on most errors, which loses what it
// printed; stdbuf -o0 makes its output unbuffered so the last lines survive.
std::vector<std::string> tetgenCommand(const fs::path& tetgen, const std::string& switches,
                                       const fs::path& input) {
  std::vector<std::string> argv;
  const fs::path stdbuf = findOnPath("stdbuf");
  if (!stdbuf.empty()) argv = {stdbuf.string(), "-o0", "-e0"};
  argv.push_back(tetgen.string());
  argv.push_back(switches);
  argv.push_back(input.string());
  return argv;
}

// The last few meaningful lines of tetgen's output, indented, for an error message.
std::string outputTail(const ProcessResult& run) {
  std::vector<std::string> lines;
  for (const std::string* text : {&run.out, &run.err}) {
    std::istringstream in(*text);
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.find_first_not_of(" \t") == std::string::npos) continue;
      if (line.find("terminate called after throwing") != std::string::npos) continue;
      if (line.rfind("Opening ", 0) == 0) continue;  // names our temporary file
      lines.push_back(line);
    }
  }
  const size_t keep = 12;
  std::string tail;
  if (lines.size() > keep) tail += "  ...\n";
  for (size_t i = lines.size() > keep ? lines.size() - keep : 0; i < lines.size(); ++i) {
    tail += "  " + lines[i] + "\n";
  }
  return tail;
}

std::string howItEnded(const ProcessResult& run) {
  if (run.exited) return "exit status " + std::to_string(run.exit_code);
  if (run.signal != 0) {
    std::string name = ::strsignal(run.signal);
    return "killed by signal " + std::to_string(run.signal) + " (" + name + ")";
  }
  return "unknown status";
}

int eleCount(const fs::path& ele) {
  Result<std::string> text = readTextFile(ele);
  if (!text) return -1;
  std::istringstream in(text.value());
  std::string line;
  while (std::getline(in, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    long count = -1;
    if (fields >> count) return count >= 0 && count <= 2'000'000'000 ? static_cast<int>(count) : -1;
  }
  return -1;
}

}  // namespace

Result<TetgenRun> runTetgen(const fs::path& tetgen, const std::string& switches,
                            const fs::path& input) {
  const fs::path dir = input.parent_path();
  fs::path base = input;
  base.replace_extension(".1");
  TetgenRun out;
  out.node = base;
  out.node += ".node";
  out.ele = base;
  out.ele += ".ele";
  std::error_code ec;
  fs::remove(out.node, ec);
  fs::remove(out.ele, ec);

  Result<ProcessResult> run = runProcess(tetgenCommand(tetgen, switches, input), dir);
  if (!run) return run.error();
  const ProcessResult& r = run.value();
  const bool ended_well = r.exited && r.exit_code == 0;
  const bool have_files = fs::exists(out.node, ec) && fs::exists(out.ele, ec);
  if (!ended_well || !have_files) {
    std::string message = "tetgen " + switches + " failed (" + howItEnded(r) +
                          (ended_well ? ", but it wrote no tetrahedra" : "") + ")";
    const std::string tail = outputTail(r);
    message += tail.empty() ? "; it printed no message (TetGen 1.5 aborts silently on many faults)"
                            : "; its last output:\n" + tail;
    if (!message.empty() && message.back() == '\n') message.pop_back();
    return Error{message};
  }
  out.tets = eleCount(out.ele);
  if (out.tets < 0) return Error{"tetgen wrote an unreadable " + out.ele.string()};
  return out;
}

Result<std::vector<std::pair<int, int>>> findSelfIntersections(const fs::path& tetgen,
                                                               const fs::path& input) {
  Result<ProcessResult> run = runProcess(tetgenCommand(tetgen, "-d", input), input.parent_path());
  if (!run) return run.error();
  // "  Facet #2513 intersects facet #8422 at triangles:" with 1-based facet numbers.
  static const std::regex pair_re(R"(Facet #(\d+) intersects facet #(\d+))");
  std::vector<std::pair<int, int>> pairs;
  const std::string& out = run.value().out;
  for (auto it = std::sregex_iterator(out.begin(), out.end(), pair_re);
       it != std::sregex_iterator(); ++it) {
    pairs.emplace_back(std::stoi((*it)[1].str()) - 1, std::stoi((*it)[2].str()) - 1);
  }
  return pairs;
}

}  // namespace torsion::meshgen
