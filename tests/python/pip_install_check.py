"""`pip install --no-build-isolation .` from the source tree into a fresh virtual environment, then
the README's Python snippet run with that environment's python from outside the tree, and the
wheel `python -m build --wheel --no-isolation` makes (ctest: python.pip_install).

What it checks: pip builds and installs the package offline (--no-index: numpy and the build
tools come from Debian through --system-site-packages); the snippet runs from another folder
with no PYTHONPATH and finds its demo scene in the installed package; torsion.data_path() is the
package's data folder and every file a bundled scene refers to is in it; the wheel holds the
package and its data, nothing else.

Speed: pip builds in a copy of the source tree's files in WORK/src (a folder of the build tree,
kept between runs: a file is rewritten only when its content changed, so a second run recompiles
only what changed), in WORK/src/_skbuild, through ccache set up as the project's scripts do
(scripts/ccache_env.sh, its base directory the copy): a fresh clone's copy has the same relative
paths as any earlier one, so its compilations hit the cache an earlier clone filled. Given the
settings of the build that runs it (--cmake-arg: its warnings as errors or not; the Release flags
are CMake's in both), pip's compile commands are that build's own, and when that build lies as
deep below its tree as scikit-build's folder below the copy (three folders: scripts/test.sh's
build/ci/release), its compilations hit what that build left in the cache.
"""

import argparse
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time
import zipfile

# Never copied from the source tree: build trees, scikit-build's and pip's own output, VCS data.
SKIPPED_TOP = re.compile(r"^(build[^/]*|_skbuild|dist|\.venv|\.git|out|results)(/|$)")
KEPT_IN_COPY = {"_skbuild"}  # what the copy keeps of its own between runs


def source_files(source):
    """The files a clone of `source` would hold, plus new files not ignored by git (relative
    paths); never those of a build tree (a top-level folder with a CMakeCache.txt, such as the
    one this test runs in). Without git: every file outside build trees."""
    build_trees = {d.name for d in source.iterdir() if (d / "CMakeCache.txt").is_file()}

    def kept(rel):
        return not SKIPPED_TOP.match(rel) and rel.split("/", 1)[0] not in build_trees

    try:
        listed = subprocess.run(
            ["git", "-C", str(source), "ls-files", "-z", "--cached", "--others",
             "--exclude-standard"], check=True, capture_output=True).stdout
        files = [f for f in listed.decode().split("\0") if f]
        return sorted(f for f in files if kept(f) and (source / f).is_file())
    except (OSError, subprocess.CalledProcessError):
        found = []
        for root, dirs, names in os.walk(source):
            rel_root = pathlib.Path(root).relative_to(source)
            dirs[:] = [d for d in dirs if kept(str(rel_root / d))]
            found += [str(rel_root / n) for n in names]
        return sorted(found)


def sync(source, copy):
    """Makes `copy` hold exactly the source's files; returns how many were written. A file whose
    bytes are unchanged keeps its time stamp; a changed one gets the current time, so ninja
    rebuilds what depends on it even if the source's time stamp is older than the last build."""
    files = source_files(source)
    wanted = set(files)
    written = 0
    for rel in files:
        src, dst = source / rel, copy / rel
        data = src.read_bytes()
        if dst.is_file() and dst.stat().st_size == len(data) and dst.read_bytes() == data:
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(data)
        shutil.copymode(src, dst)
        written += 1
    for root, dirs, names in os.walk(copy, topdown=True):
        rel_root = pathlib.Path(root).relative_to(copy)
        if rel_root == pathlib.Path("."):
            dirs[:] = [d for d in dirs if d not in KEPT_IN_COPY]
        for name in names:
            if str(rel_root / name) not in wanted:
                (pathlib.Path(root) / name).unlink()
    return written


def readme_snippet(source):
    """The README's pip block: (its commands, the Python script it runs from outside the tree)."""
    readme = (source / "README.md").read_text()
    block = re.search(r"```sh\n((?:[^\n]*\n)*?[^\n]*pip install --no-build-isolation \.\n)"
                      r"([^\n]*python - <<'EOF'\n)(.*?)\nEOF\n```", readme, re.S)
    if not block:
        sys.exit("README.md: no ```sh block with `pip install --no-build-isolation .` followed by "
                 "a `python - <<'EOF'` script")
    commands, runner, script = block.groups()
    return commands + runner, script


# Run in the virtual environment after the README's snippet, from outside the tree.
CHECKS = r"""
import json, pathlib, sys, sysconfig
import torsion
site = pathlib.Path(sysconfig.get_paths()["platlib"]).resolve()
package = pathlib.Path(torsion.__file__).resolve().parent
assert package == site / "torsion", (package, site)
assert pathlib.Path(sys.prefix).resolve() == pathlib.Path(sys.argv[1]).resolve(), sys.prefix
data = torsion.data_path()
assert data.resolve() == package / "data", data
scenes = sorted((data / "demos" / "scenes").glob("*.json"))
assert len(scenes) == int(sys.argv[2]), (len(scenes), sys.argv[2])

def strings(value):
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from strings(v)
    elif isinstance(value, list):
        for v in value:
            yield from strings(v)

referred = 0
for scene in scenes:
    for s in strings(json.loads(scene.read_text())):
        if s.startswith("../"):
            assert (scene.parent / s).is_file(), (scene.name, s)
            referred += 1
assert referred > 0
world = torsion.World.from_scene("drop", threads=1)
world.step(2)
print(f"installed: {package}; data: {data}; {len(scenes)} scenes, {referred} files they refer to")
"""


def run(command, what, **kwargs):
    started = time.monotonic()
    print(f"== {what}: {' '.join(map(str, command))}", flush=True)
    result = subprocess.run(command, **kwargs)
    seconds = time.monotonic() - started
    print(f"== {what}: exit {result.returncode}, {seconds:.1f} s", flush=True)
    if result.returncode != 0:
        sys.exit(f"{what} failed (exit {result.returncode})")
    return seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source", type=pathlib.Path, required=True, help="the source tree")
    parser.add_argument("--python", default="/usr/bin/python3",
                        help="the interpreter the virtual environment is made from")
    parser.add_argument("--version", required=True, help="the version torsion must report")
    parser.add_argument("--cmake-arg", action="append", default=[],
                        help="a CMake setting of the build running the test, passed to pip's")
    parser.add_argument("--work", type=pathlib.Path, required=True,
                        help="the test's folder (the copy, its build, the environment)")
    args = parser.parse_args()
    source, work = args.source.resolve(), args.work.resolve()
    if work == source:
        sys.exit(f"{work}: the test's folder must not be the source tree itself")
    work.mkdir(parents=True, exist_ok=True)

    started = time.monotonic()
    copy, venv, run_dir, dist = work / "src", work / "venv", work / "run", work / "dist"
    copy.mkdir(exist_ok=True)
    written = sync(source, copy)
    print(f"== source copied to {copy}: {written} file(s) written", flush=True)
    for folder in (venv, run_dir, dist):
        shutil.rmtree(folder, ignore_errors=True)
    # A kept build folder is configured afresh (its objects stay): the settings are this run's.
    for cache in copy.glob("_skbuild/*/cmake-build/CMakeCache.txt"):
        cache.unlink()
    run_dir.mkdir()

    commands, script = readme_snippet(source)
    # The README's command line, run here with the test's paths; --no-index: nothing downloaded.
    assert re.search(r"python3 -m venv --system-site-packages ", commands), commands
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "TORSION_SCENE_PATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["CMAKE_BUILD_PARALLEL_LEVEL"] = env.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
    # The running build's settings (module docstring). scikit-build puts CMAKE_ARGS, split at
    # blanks, before setup.py's own arguments.
    env["CMAKE_ARGS"] = " ".join([env.get("CMAKE_ARGS", "")] + args.cmake_arg).strip()
    times = {}
    times["venv"] = run([args.python, "-m", "venv", "--system-site-packages", venv],
                        "fresh virtual environment", env=env)
    python = venv / "bin" / "python"
    pip = [python, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir",
           "."]
    # In the copy, with the compiler cache set up as the project's scripts do; its hits and misses
    # are printed after pip's output.
    times["pip install"] = run(
        ["bash", "-c", 'source scripts/ccache_env.sh && "$@"; rc=$?; ccache_report; exit $rc',
         "pip"] + pip, "pip install --no-build-isolation .", cwd=copy, env=env)
    times["README snippet"] = run([python, "-c", script], "README's snippet, outside the tree",
                                  cwd=run_dir, env=env)
    scene_count = len(list((source / "demos" / "scenes").glob("*.json")))
    times["checks"] = run([python, "-c", CHECKS, venv, str(scene_count)],
                          "installed package and data", cwd=run_dir, env=env)
    version = subprocess.run([python, "-c", "import torsion; print(torsion.__version__)"],
                             cwd=run_dir, env=env, capture_output=True, text=True).stdout.strip()
    if version != args.version:
        sys.exit(f"torsion.__version__ is {version!r}, expected {args.version!r}")

    # The wheel `python -m build` makes (python3-build): the package and its data, nothing else.
    times["wheel"] = run(
        [python, "-m", "build", "--wheel", "--no-isolation", "--outdir", dist, "."],
        "python -m build --wheel --no-isolation", cwd=copy, env=env)
    wheels = list(dist.glob("torsion-*.whl"))
    if len(wheels) != 1:
        sys.exit(f"{dist}: expected one torsion wheel, found {wheels}")
    names = zipfile.ZipFile(wheels[0]).namelist()
    outside = [n for n in names if not n.startswith(("torsion/", "torsion-"))]
    expected = ["torsion/__init__.py", "torsion/__init__.pyi", "torsion/errors.py",
                "torsion/viewer.py", "torsion/py.typed", "torsion/data/demos/scenes/drop.json",
                "torsion/data/assets/meshes/cylinder_2430.node"]
    missing = [n for n in expected if n not in names]
    modules = [n for n in names if re.fullmatch(r"torsion/_torsion\..*\.so", n)]
    if outside or missing or len(modules) != 1:
        sys.exit(f"{wheels[0].name}: outside the package: {outside}; missing: {missing}; "
                 f"modules: {modules}")
    print(f"== {wheels[0].name}: {len(names)} files, all in the package")
    print("== wall time: " + ", ".join(f"{k} {v:.1f} s" for k, v in times.items()) +
          f"; total {time.monotonic() - started:.1f} s")
    print("pip install OK")


if __name__ == "__main__":
    main()
