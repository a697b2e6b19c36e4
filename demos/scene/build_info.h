#pragma once
// What was built: the version and the source's git commit, written into `torsion --version` and
// every summary.json. The definitions are generated at build time (cmake/TorsionBuildInfo.cmake).

namespace torsion::scene {

/// The project version from CMakeLists.txt, e.g. "0.1.0".
const char* torsionVersion();

/// The git commit the program was built from (12 hex digits), "-dirty" appended when tracked
/// files differed from it, or "unknown" when the source was not a git checkout.
const char* torsionGitCommit();

}  // namespace torsion::scene
