// libFuzzer target for the TetGen reader (parseTetGen), then buildTetMesh and the TetGen writer.
// The input holds both files: .node text, the line "====", .ele text. Without that separator it is
// cut in half, so plain mutations still reach the .ele parser.

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>

#include "fuzz_checks.h"
#include "torsion/mesh/tetgen_format.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kSeparator = "\n====\n";
  std::string_view node = input.substr(0, size / 2);
  std::string_view ele = input.substr(size / 2);
  if (const size_t cut = input.find(kSeparator); cut != std::string_view::npos) {
    node = input.substr(0, cut);
    ele = input.substr(cut + kSeparator.size());
  }

  torsion::Result<torsion::RawTetMesh> raw =
      torsion::parseTetGen(node, "fuzz.node", ele, "fuzz.ele");
  if (!raw.ok()) {
    const std::string& message = raw.error().message;
    TORSION_FUZZ_CHECK(!message.empty());
    TORSION_FUZZ_CHECK(torsion::fuzz::startsWith(message, "fuzz.node:") ||
                       torsion::fuzz::startsWith(message, "fuzz.ele:"));
    return 0;
  }
  TORSION_FUZZ_CHECK(raw.value().element_file == "fuzz.ele");
  torsion::fuzz::buildAndCheck(std::move(raw).value());
  return 0;
}
