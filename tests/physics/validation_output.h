#pragma once
// Physics tests write the data behind docs/validation.md when TORSION_VALIDATION_OUT names a
// directory (docs/figures/make_validation_figures.sh sets it); otherwise they write nothing.

#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

namespace torsion::test {

/// An open CSV file in $TORSION_VALIDATION_OUT, or null when the variable is unset.
inline std::unique_ptr<std::ofstream> validationCsv(const std::string& name,
                                                    const std::string& header) {
  const char* dir = std::getenv("TORSION_VALIDATION_OUT");
  if (dir == nullptr || *dir == '\0') return nullptr;
  auto out = std::make_unique<std::ofstream>(std::string(dir) + "/" + name);
  *out << header << "\n";
  out->precision(10);
  return out;
}

}  // namespace torsion::test
