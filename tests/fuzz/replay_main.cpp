// Stand-in for libFuzzer's main in builds without it (gcc, normal test runs): calls the target's
// LLVMFuzzerTestOneInput once on every file named on the command line or found (not recursively)
// in a directory named there, in name order. Exits non-zero when given no input at all; a failed
// invariant traps, which ctest reports as a failure. Usage: replay_<format> <dir|file>...

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

namespace fs = std::filesystem;

bool replay(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "replay: cannot read %s\n", file.c_str());
    return false;
  }
  // A buffer of exactly the input's size, as libFuzzer passes it, so that a reader running off the
  // end is caught by AddressSanitizer when it is on.
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  std::fprintf(stderr, "replay: %s (%zu bytes)\n", file.c_str(), bytes.size());
  std::fflush(stderr);
  LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg(argv[i]);
    std::error_code error;
    if (fs::is_directory(arg, error)) {
      std::vector<fs::path> entries;
      for (const fs::directory_entry& entry : fs::directory_iterator(arg)) {
        if (entry.is_regular_file()) entries.push_back(entry.path());
      }
      std::sort(entries.begin(), entries.end());
      files.insert(files.end(), entries.begin(), entries.end());
    } else if (fs::is_regular_file(arg, error)) {
      files.push_back(arg);
    } else {
      std::fprintf(stderr, "replay: %s is neither a file nor a directory\n", argv[i]);
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s <corpus dir | input file>...  (found no input)\n", argv[0]);
    return 2;
  }
  for (const fs::path& file : files) {
    if (!replay(file)) return 1;
  }
  std::fprintf(stderr, "replay: %zu inputs passed\n", files.size());
  return 0;
}
