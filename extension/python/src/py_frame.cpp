#include "py_frame.h"

namespace torsion::python {

render::FrameData captureWorldFrame(PyWorld& world) {
  render::FrameData frame = render::captureFrame(world.scene());
  const std::vector<Hand*> hands = world.hands();  // the scene's, then those added in code
  for (size_t i = world.scene().hands.size(); i < hands.size(); ++i)
    render::addHand(frame, *hands[i], hands[i]->name(), hands[i]->goal());
  return frame;
}

}  // namespace torsion::python
