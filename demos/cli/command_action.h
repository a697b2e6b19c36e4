#pragma once
// A subcommand's work, chosen while the command line is parsed and run by main afterwards. Its
// return value is the process exit code (0 success, 1 bad input or failure; `torsion run` and
// `torsion view` document more), handed back to main instead of kept in a global.

#include <functional>

namespace torsion::cli {

using CommandAction = std::function<int()>;

}  // namespace torsion::cli
