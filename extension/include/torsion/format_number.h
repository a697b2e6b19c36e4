#pragma once
// Numbers in messages: %g, so 1e-9 reads "1e-09" and 1e300 "1e+300", never std::to_string's
// "0.000000" or 300 digits.

#include <cstdio>
#include <string>

namespace torsion {

inline std::string formatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace torsion
