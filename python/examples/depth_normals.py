#!/usr/bin/env python3
"""Casts camera rays at a mesh and writes a depth image and a normal image (PNG).

    python3 examples/depth_normals.py [mesh.obj] [--width 640] [--height 480] [-o out_prefix]

The default mesh is the Stanford bunny of Debian's glmark2-data package (/usr/share/glmark2/models/bunny.obj).
Needs only numpy and vkas: the OBJ reader and the PNG writer (zlib) are below.
"""

import argparse
import struct
import sys
import time
import zlib

import numpy as np

import vkas

DEFAULT_MESH = "/usr/share/glmark2/models/bunny.obj"


def load_obj(path):
    """Vertices (N, 3) float32 and triangles (M, 3) uint32 of a Wavefront OBJ file (v and f lines; polygons are
    fanned into triangles; v/vt/vn references and negative indices are understood)."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                idx = [i - 1 if i > 0 else len(vertices) + i for i in idx]
                faces += [[idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1)]
    return np.array(vertices, dtype=np.float32), np.array(faces, dtype=np.uint32)


def write_png(path, image):
    """image: (H, W) or (H, W, 3) uint8."""
    h, w = image.shape[:2]
    channels = 1 if image.ndim == 2 else image.shape[2]
    raw = b"".join(b"\x00" + image[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 0 if channels == 1 else 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6))
                + chunk(b"IEND", b""))


def camera_rays(vertices, width, height, fov_degrees=40.0):
    """Rays of a pinhole camera looking at the mesh's bounding box from the front (+z), slightly above."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    center, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    eye = center + np.array([0.3, 0.35, 1.0]) / np.linalg.norm([0.3, 0.35, 1.0]) * radius * 2.8
    forward = (center - eye) / np.linalg.norm(center - eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    s = np.tan(np.radians(fov_degrees) / 2)
    x = (np.arange(width) + 0.5) / width * 2 - 1
    y = 1 - (np.arange(height) + 0.5) / height * 2
    xx, yy = np.meshgrid(x * s * width / height, y * s)
    d = forward + xx[..., None] * right + yy[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.tile(eye.astype(np.float32), (width * height, 1))  # C-contiguous, as vkas reads float32 arrays in place
    return o, d.reshape(-1, 3).astype(np.float32)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=DEFAULT_MESH)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("-o", "--output", default="bunny", help="prefix of the PNG files (default: bunny)")
    args = ap.parse_args(argv)

    vertices, faces = load_obj(args.mesh)
    dev = vkas.Device()
    t0 = time.perf_counter()
    scene = vkas.Scene(dev, vertices, faces)
    t1 = time.perf_counter()
    origins, directions = camera_rays(vertices, args.width, args.height)
    hits = scene.intersect(origins, directions)
    t2 = time.perf_counter()
    print(f"{args.mesh}: {len(faces)} triangles, built in {1e3 * (t1 - t0):.1f} ms; "
          f"{len(origins)} rays in {1e3 * (t2 - t1):.1f} ms, {int(hits.hit.sum())} hits")

    shape = (args.height, args.width)
    hit = hits.hit
    # depth: near is bright, background black
    depth = np.zeros(len(hit))
    if hit.any():
        t = hits.t[hit]
        lo, hi = t.min(), t.max()
        depth[hit] = 1.0 - 0.8 * (t - lo) / max(hi - lo, 1e-12)
    write_png(f"{args.output}-depth.png", (depth.reshape(shape) * 255).astype(np.uint8))
    # normals: the geometric normal of the triangle hit, facing the camera, mapped from [-1, 1] to [0, 255]
    normals = np.zeros((len(hit), 3))
    tri = vertices[faces[hits.primitive_id[hit]]].astype(np.float64)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= np.where(np.einsum("ij,ij->i", n, directions[hit]) > 0, -1.0, 1.0)[:, None]
    normals[hit] = n
    image = np.where(hit[:, None], (normals * 0.5 + 0.5) * 255, 0).astype(np.uint8)
    write_png(f"{args.output}-normals.png", image.reshape(*shape, 3))
    print(f"wrote {args.output}-depth.png and {args.output}-normals.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
