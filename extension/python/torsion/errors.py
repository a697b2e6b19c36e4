"""The exceptions torsion raises. Each carries the message the `torsion` command prints, word for
word, plus the place it names, parsed out of it."""

import re


class Error(RuntimeError):
    """Base of torsion's own errors."""


class SceneError(Error):
    """A scene file that cannot be read, parsed or built.

    ``file`` is the scene file; ``key`` the entry the message names first (e.g. ``"bodies[0]"``
    or ``"solver"``), or None; ``line`` the 1-based line of a JSON syntax error, or None.
    """

    def __init__(self, message):
        super().__init__(message)
        self.message = message
        match = re.match(r"(.+?\.json)(?::(\d+):\d+)?:\s*(\S+?)(?::|\s|$)", message)
        self.file = match.group(1) if match else None
        self.line = int(match.group(2)) if match and match.group(2) else None
        self.key = match.group(3) if match and not self.line else None


class MeshError(Error):
    """A mesh file (or nodes/tets arrays) that cannot be read or is not a valid tet mesh.

    ``file`` and ``line`` (1-based, or None) name where the fault is.
    """

    def __init__(self, message):
        super().__init__(message)
        self.message = message
        match = None
        for match in re.finditer(r"([^\s:'\"]+\.(?:node|ele|msh|vtk|face|smesh)|<tets array>):(\d+)?", message):
            pass
        self.file = match.group(1) if match else None
        self.line = int(match.group(2)) if match and match.group(2) else None


class UnstableError(Error):
    """A step that failed (blow-up, inverted elements, a rigid body gone non-finite).

    ``body`` names the body (or rigid body), ``step`` the 1-based step that failed. The world keeps
    its last good state and refuses further steps (restore_state to go back).
    """

    def __init__(self, message):
        super().__init__(message)
        self.message = message
        body = re.search(r"body '([^']*)'", message)
        step = re.search(r"step (\d+)", message)
        self.body = body.group(1) if body else None
        self.step = int(step.group(1)) if step else None
