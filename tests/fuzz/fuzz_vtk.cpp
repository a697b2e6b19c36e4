// libFuzzer target for the legacy VTK reader (parseVtk), then buildTetMesh and the TetGen writer.

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>

#include "fuzz_checks.h"
#include "torsion/mesh/vtk_format.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  torsion::Result<torsion::RawTetMesh> raw = torsion::parseVtk(input, "fuzz.vtk");
  if (!raw.ok()) {
    torsion::fuzz::checkError(raw.error(), "fuzz.vtk");
    return 0;
  }
  torsion::fuzz::buildAndCheck(std::move(raw).value());
  return 0;
}
