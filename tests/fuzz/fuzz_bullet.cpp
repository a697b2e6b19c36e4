// libFuzzer target for a scene's .bullet file (bullet_file_import.h): the input is the file, and
// a scene naming it is parsed. Bullet's reader runs in a child process, so whatever the bytes do
// to it, this process must end with either an error naming the scene, the key and the file, or
// rigid bodies that passed the scene's checks (finite poses, unit rotations). Never a crash or a
// hang here. The file lives in memory (memfd), named by its /proc/self/fd path, which the child
// inherits.
//
// Coverage feedback comes from this process only (the child's is lost with it): the fuzzer drives
// the isolation and the checks of what comes back, not Bullet's parser itself.

#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_checks.h"
#include "scene_parser.h"

#ifndef TORSION_FUZZ_MESH
#error "TORSION_FUZZ_MESH: a tetgen .node file the scene's FEM body is read from"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const int fd = memfd_create("fuzz.bullet", MFD_CLOEXEC);
  TORSION_FUZZ_CHECK(fd >= 0);
  size_t written = 0;
  while (written < size) {
    const ssize_t n = write(fd, data + written, size - written);
    TORSION_FUZZ_CHECK(n > 0);
    written += static_cast<size_t>(n);
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  const std::string scene =
      R"({"bodies": [{"name": "slab", "mesh": ")" + std::string(TORSION_FUZZ_MESH) +
      R"(", "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3, "density": 300}}],
      "bullet_file": ")" +
      path + R"("})";
  const torsion::Result<torsion::scene::SceneSpec> spec =
      torsion::scene::parseScene(scene, "fuzz.json", "/");
  if (spec.ok()) {
    for (const torsion::scene::RigidBodySpec& body : spec.value().rigid_bodies) {
      TORSION_FUZZ_CHECK(body.pose.origin.allFinite());
      TORSION_FUZZ_CHECK(std::abs(body.pose.rotation.norm() - 1.0) < 1e-9);
      TORSION_FUZZ_CHECK(std::isfinite(body.mass) && body.mass >= 0);
    }
  } else {
    torsion::fuzz::checkError(spec.error(), "fuzz.json: bullet_file: " + path + ": ");
  }
  close(fd);
  return 0;
}
