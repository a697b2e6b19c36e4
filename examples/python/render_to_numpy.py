#!/usr/bin/env python3
"""Render a world headless (OSMesa) into numpy arrays and save a strip of frames.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/render_to_numpy.py --out frames

The twist of twist_cylinder_2430, coloured by von Mises stress, every 100 steps; the frames are
(height, width, 3) uint8 arrays, put side by side into twist_frames.png.
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import torsion  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=".")
    parser.add_argument("--frames", type=int, default=4)
    parser.add_argument("--every", type=int, default=100, help="steps between frames")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    frames = []
    for _ in range(args.frames):
        world.step(args.every)
        image = world.render(320, 240, camera={"yaw": 0.8, "pitch": 0.3})
        frames.append(image)
        stress = world.body("cylinder").von_mises_stress()
        print(f"t = {world.time:5.2f} s: image {image.shape} {image.dtype}, "
              f"peak von Mises {stress.max():.0f} Pa")
    strip = np.concatenate(frames, axis=1)
    plt.imsave(out / "twist_frames.png", strip)
    print(f"wrote {out / 'twist_frames.png'}")


if __name__ == "__main__":
    main()
