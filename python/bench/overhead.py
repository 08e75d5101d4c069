#!/usr/bin/env python3
"""The Python package's overhead: TopLevel.intersect on 1M rays against vkasTraceRays alone on the same rays.

    python3 bench/overhead.py [--rays 1000000] [--repeats 7] [--threads 0] [--validation on|off]

Both run on one device and one structure (the Stanford bunny of Debian's glmark2-data, 69,666 triangles). The C
side is the extension's time_trace_rays hook: vkasTraceRays called directly on rays packed beforehand
(VkasRay records), nothing else timed. The Python side is the whole public call: argument checks, the packing and
ray checks, vkasTraceRays, and the unpacking into the Hits arrays. Best of --repeats runs each, interleaved. Not a test:
docs/PERFORMANCE.md ("Python overhead (issue 19)") records its numbers.
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
from depth_normals import DEFAULT_MESH, camera_rays, load_obj  # noqa: E402

import vkas  # noqa: E402


def best(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--validation", choices=["on", "off"], default="on")
    ap.add_argument("--mesh", default=DEFAULT_MESH)
    args = ap.parse_args()

    vertices, faces = load_obj(args.mesh)
    dev = vkas.Device(validation=args.validation == "on", threads=args.threads)
    scene = vkas.Scene(dev, vertices, faces)
    tlas = scene.top_level
    side = int(np.sqrt(args.rays))
    cam_o, cam_d = camera_rays(vertices, side, args.rays // side)
    rng = np.random.default_rng(19)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    rnd_o = rng.uniform(lo - (hi - lo), hi + (hi - lo), (args.rays, 3)).astype(np.float32)
    rnd_d = (rng.uniform(lo, hi, (args.rays, 3)) - rnd_o).astype(np.float32)

    print(f"vkas {vkas.__version__}, Python {platform.python_version()}, numpy {np.__version__}, "
          f"{os.cpu_count()} cores, device threads {dev.threads}, validation {args.validation}")
    print(f"mesh {os.path.basename(args.mesh)}: {len(faces)} triangles; best of {args.repeats}")
    print(f"{'rays':<28}{'count':>9}{'C vkasTraceRays':>18}{'Python intersect':>18}{'overhead':>10}")
    for name, o, d in (("camera (coherent)", cam_o, cam_d), ("random (incoherent)", rnd_o, rnd_d)):
        t0 = np.zeros(len(o), np.float32)
        t1 = np.full(len(o), np.inf, np.float32)
        packed = dev._core.pack_rays(o, d, t0, t1)
        c = py = float("inf")
        for _ in range(args.repeats):  # interleaved, so that a busy moment of a shared machine hits both alike
            c = min(c, dev._core.time_trace_rays(tlas._s, packed, 0, 0xFF, False, 1))
            py = min(py, best(lambda: tlas.intersect(o, d), 1))
        print(f"{name:<28}{len(o):>9}{1e3 * c:>15.1f} ms{1e3 * py:>15.1f} ms{100 * (py / c - 1):>9.1f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
