// libFuzzer target for the Gmsh .msh reader (parseGmsh), then buildTetMesh and the TetGen writer.

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>

#include "fuzz_checks.h"
#include "torsion/mesh/gmsh_format.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  torsion::Result<torsion::RawTetMesh> raw = torsion::parseGmsh(input, "fuzz.msh");
  if (!raw.ok()) {
    torsion::fuzz::checkError(raw.error(), "fuzz.msh");
    return 0;
  }
  torsion::fuzz::buildAndCheck(std::move(raw).value());
  return 0;
}
