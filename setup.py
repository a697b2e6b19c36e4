"""The torsion Python package built by pip (`pip install --no-build-isolation .`) through
scikit-build: CMake builds the library, the demos' scene loader, renderer and series writer, and
the module, and installs the package with its demo data (extension/python/CMakeLists.txt,
`if(SKBUILD)`).

Only the package goes into the wheel: the rest of what `cmake --install` would put into a prefix
(headers, static libraries, the CMake package) stays in scikit-build's scratch folder (_skbuild/).
Options for CMake can be added with the environment variable CMAKE_ARGS (scikit-build's).
"""

import os
import pathlib
import re

from skbuild import setup

HERE = pathlib.Path(__file__).resolve().parent
# The version is the CMake project's (CMakeLists.txt), as torsion.__version__ reports it.
VERSION = re.search(r"project\(Torsion VERSION ([0-9.]+)",
                    (HERE / "CMakeLists.txt").read_text()).group(1)
# CMake installs into <scratch>/extension/python: the package lands where package_dir says it is.
PACKAGE_ROOT = "extension/python"


def package_files_only(manifest):
    """The installed files that belong to the package (torsion/...), nothing else."""
    package = PACKAGE_ROOT + "/torsion/"
    return [path for path in manifest if package in path.replace(os.sep, "/")]


setup(
    name="torsion",
    version=VERSION,
    description="Corotational FEM soft bodies, hand-plane torsion and haptic coupling for Bullet",
    license="Zlib",
    python_requires=">=3.9",
    install_requires=["numpy"],
    packages=["torsion"],
    package_dir={"": PACKAGE_ROOT},
    cmake_install_dir=PACKAGE_ROOT,
    cmake_process_manifest_hook=package_files_only,
    cmake_args=[
        "-DCMAKE_BUILD_TYPE=Release",
        # The library and the module only: no tests, benchmarks, tool, viewer or mesh generation.
        "-DTORSION_BUILD_TESTS=OFF",
        "-DTORSION_BUILD_BENCHMARKS=OFF",
        "-DTORSION_BUILD_CLI=OFF",
        "-DTORSION_PYTHON=ON",
        # Batches of 8 sources: a clean build takes half the time on few cores.
        "-DTORSION_UNITY_BUILD=ON",
    ],
    zip_safe=False,
)
