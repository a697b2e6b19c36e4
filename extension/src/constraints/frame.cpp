#include "torsion/constraints/frame.h"

#include <cmath>
#include <sstream>

namespace torsion {

Result<Frame> checkedFrame(const Frame& frame, const std::string& what) {
  if (!frame.origin.allFinite()) return Error{what + "'s origin is not finite"};
  const double norm = frame.rotation.norm();
  if (!(std::abs(norm - 1) <= 1e-6)) {
    std::ostringstream message;
    message << what << "'s rotation is not a unit quaternion (w, x, y, z) = (" << frame.rotation.w()
            << ", " << frame.rotation.x() << ", " << frame.rotation.y() << ", "
            << frame.rotation.z() << "), norm " << norm;
    return Error{message.str()};
  }
  Frame unit = frame;
  unit.rotation.normalize();
  return unit;
}

}  // namespace torsion
