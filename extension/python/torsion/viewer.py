"""Watching a world your script steps: a window like `torsion view`'s, after MuJoCo's
`mujoco.viewer.launch_passive`.

    import torsion, torsion.viewer
    world = torsion.World.from_scene("twist_cylinder_2430")
    with torsion.viewer.launch_passive(world) as viewer:
        while viewer.is_running() and world.time < 2.0:
            world.step()
            viewer.sync()          # draws the world as it is now
    # the script goes on when the user closes the window

The viewer never steps or changes the world. Everything happens inside sync(), on the calling
thread: it delivers the window's input (camera drags, wheel, F, Q or Escape), reads the world and
draws it, then returns. Between two syncs the window is not redrawn. See docs/python.md,
"Watching a world".
"""

from types import TracebackType
from typing import Optional, Type

import numpy as np
import numpy.typing as npt

from . import _torsion
from ._torsion import World

__all__ = ["DisplayError", "PassiveViewer", "launch_passive"]


class DisplayError(RuntimeError):
    """No window could be opened: no display (DISPLAY unset: run under xvfb-run, or use
    World.render() for pictures without one), no OpenGL 2.1 context, or a build of torsion
    without GLFW."""


class PassiveViewer:
    """A window on a World that the script steps; launch_passive() opens one.

    Call its methods from the thread that launched it. It keeps its world alive.
    """

    def __init__(self, world: World, *, width: int = 1024, height: int = 720,
                 title: Optional[str] = None) -> None:
        try:
            self._viewer = _torsion._PassiveViewer(world, width, height, title or "")
        except RuntimeError as error:
            raise DisplayError(str(error)) from None

    def sync(self) -> None:
        """Delivers the window's input, then draws the world as it is now and shows it. Once
        the window is closed (by the user, Q or Escape, or close()), does nothing. Raises
        RuntimeError while the world steps in another thread."""
        self._viewer.sync()

    def is_running(self) -> bool:
        """False once the window is closed: by the user (seen at the next sync()), Q or Escape,
        or close()."""
        return self._viewer.is_running()

    def close(self) -> None:
        """Closes the window; the world is untouched. Closing again does nothing."""
        self._viewer.close()

    @property
    def frame_count(self) -> int:
        """Frames sync() has drawn."""
        return self._viewer.frame_count

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second between syncs that found the world stepped,
        smoothed over about ten of them (the HUD shows it); 0 before two such syncs."""
        return self._viewer.real_time_factor

    def capture(self) -> npt.NDArray[np.uint8]:
        """The last frame sync() drew, drawn again and read back from the window: (height,
        width, 3) uint8. RuntimeError before the first sync() and once closed."""
        return self._viewer.capture()

    def __enter__(self) -> "PassiveViewer":
        return self

    def __exit__(self, kind: Optional[Type[BaseException]], value: Optional[BaseException],
                 traceback: Optional[TracebackType]) -> None:
        self.close()


def launch_passive(world: World, *, width: int = 1024, height: int = 720,
                   title: Optional[str] = None) -> PassiveViewer:
    """Opens a window on `world` (a torsion.World, from a scene or built in code) and returns
    at once; the script keeps stepping the world and calls sync() to show it. width and height
    in pixels, within [64, 16384]; title defaults to the scene's name.

    DisplayError when no window can be opened (no display, no OpenGL 2.1, no GLFW in this
    build)."""
    return PassiveViewer(world, width=width, height=height, title=title)
