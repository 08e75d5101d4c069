"""A brute-force numpy oracle in double precision, and test meshes.

The oracle tests every ray against every primitive in float64. Near a triangle's edges (or a sphere's silhouette)
float64 and vkas's float32 watertight test may legitimately disagree, so each (ray, primitive) pair is classified
as a definite hit, a definite miss, or ambiguous (within a margin of an edge, of tmin/tmax, or of another hit's t),
and tests compare only rays without ambiguous pairs; shared edges and vertices have tests of their own
(test_watertight.py), which need no oracle.
"""

import numpy as np

EDGE_MARGIN = 1e-4  # barycentric margin: closer to an edge than this is ambiguous
T_MARGIN = 1e-4  # relative t margin (against tmin/tmax and between hits of one ray)


class Classified:
    """Per (ray, primitive): definite hit / ambiguous, with t, barycentrics and facing of the hits."""

    def __init__(self, hit, ambiguous, t, u, v, front):
        self.hit, self.ambiguous, self.t, self.u, self.v, self.front = hit, ambiguous, t, u, v, front

    def clean_rays(self):
        """Rays with no ambiguous pair and no two hits within T_MARGIN of each other."""
        ok = ~self.ambiguous.any(axis=1)
        ts = np.where(self.hit, self.t, np.inf)
        ts = np.sort(ts, axis=1)
        if ts.shape[1] > 1:
            a, b = ts[:, :-1], ts[:, 1:]
            with np.errstate(invalid="ignore"):
                close = np.isfinite(b) & (b - a <= T_MARGIN * np.maximum(1.0, np.abs(b)))
            ok &= ~close.any(axis=1)
        return ok

    def closest(self):
        ts = np.where(self.hit, self.t, np.inf)
        prim = np.argmin(ts, axis=1)
        t = ts[np.arange(len(ts)), prim]
        prim = np.where(np.isfinite(t), prim, -1)
        return prim, t


def _dot(a, b):
    return (a * b).sum(axis=-1)


def triangles_vs_rays(tri, origins, directions, tmin, tmax):
    """tri: (M, 3, 3) float64 world-space triangles; rays (R, 3) float64; tmin/tmax (R,).

    The specification's triangle test: t in (tmin, tmax) strictly; barycentrics (u, v) of v1 and v2; front facing
    when N = (v1 - v0) x (v2 - v0) points against the direction. Edge-on triangles never hit."""
    o = origins[:, None, :]
    d = directions[:, None, :]
    v0, v1, v2 = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(d, e2)
    det = _dot(e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - v0
        u = _dot(s, p) * inv
        q = np.cross(s, e1)
        v = _dot(d, q) * inv
        t = _dot(e2, q) * inv
    w = 1.0 - u - v
    scale = np.linalg.norm(np.cross(e1, e2), axis=-1) * np.linalg.norm(directions, axis=-1)[:, None]
    edge_on = np.abs(det) <= 1e-9 * np.maximum(scale, 1e-300)
    bmin = np.minimum(np.minimum(u, v), w)
    t0, t1 = tmin[:, None], tmax[:, None]
    tol = T_MARGIN * np.maximum(1.0, np.abs(t))
    inside_t = (t > t0 + tol) & (t < t1 - tol)
    near_t = (np.abs(t - t0) <= tol) | (np.abs(t - t1) <= tol)
    hit = ~edge_on & (bmin > EDGE_MARGIN) & inside_t
    ambiguous = ~edge_on & (np.abs(bmin) <= EDGE_MARGIN) & (t > t0 - tol) & (t < t1 + tol)
    ambiguous |= ~edge_on & (bmin > -EDGE_MARGIN) & near_t
    # Nearly edge-on triangles are ambiguous too (vkas decides them in float).
    nearly = (np.abs(det) <= 1e-6 * np.maximum(scale, 1e-300)) & ~hit
    ambiguous |= nearly & (bmin > -EDGE_MARGIN)
    n = np.cross(e1, e2)
    front = _dot(n, d) < 0
    return Classified(hit, ambiguous, np.where(hit, t, np.inf), u, v, front)


def spheres_vs_rays(centers, radii, origins, directions, tmin, tmax):
    """Entry points only: a ray starting inside a sphere (or meeting it only before tmin) does not hit it."""
    o = origins[:, None, :]
    d = directions[:, None, :]
    oc = o - centers[None]
    a = _dot(d, d)
    b = _dot(oc, d)
    c = _dot(oc, oc) - radii[None] ** 2
    disc = b * b - a * c
    with np.errstate(invalid="ignore"):
        t = (-b - np.sqrt(np.maximum(disc, 0))) / a
    t0, t1 = tmin[:, None], tmax[:, None]
    tol = T_MARGIN * np.maximum(1.0, np.abs(t))
    rel = disc / np.maximum(a * radii[None] ** 2, 1e-300)
    hit = (rel > 1e-4) & (t > t0 + tol) & (t < t1 - tol)
    ambiguous = (np.abs(rel) <= 1e-4) | ((rel > 0) & ((np.abs(t - t0) <= tol) | (np.abs(t - t1) <= tol)))
    zeros = np.zeros_like(t)
    return Classified(hit, ambiguous, np.where(hit, t, np.inf), zeros, zeros, np.zeros_like(hit))


def apply(transform, points):
    t = np.asarray(transform, dtype=np.float64)
    return points @ t[:, :3].T + t[:, 3]


# ---------------------------------------------------------------------------------------------------------------
# Meshes

def random_soup(rng, count, size=0.3):
    """count random triangles in [-1, 1]^3, each within a box of `size`."""
    centers = rng.uniform(-1, 1, (count, 1, 3))
    return (centers + rng.uniform(-size, size, (count, 3, 3))).astype(np.float32)


def grid(n, z=0.0, scale=1.0 / 8):
    """An n x n grid of squares, two triangles each, on exactly representable coordinates (multiples of 1/8)."""
    ij = np.stack(np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="xy"), -1).reshape(-1, 2)
    vertices = np.column_stack([ij * scale, np.full(len(ij), z)]).astype(np.float32)
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            b, c = a + 1, a + n + 1
            faces += [[a, b, c + 1], [a, c + 1, c]]
    return vertices, np.array(faces, dtype=np.uint32)


def icosphere(subdivisions=2, jitter=0.0, rng=None):
    """A closed, convex-ish triangle mesh around the origin (radius about 1), consistently oriented outwards."""
    t = (1.0 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
         [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
         [8, 6, 7], [9, 8, 1]]
    verts = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(subdivisions):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        nf = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = nf
    verts = np.array(verts)
    if jitter:
        verts *= 1.0 + rng.uniform(-jitter, jitter, (len(verts), 1))
    return verts.astype(np.float32), np.array(faces, dtype=np.uint32)


def random_rays(rng, count, spread=1.5):
    origins = rng.uniform(-spread, spread, (count, 3))
    targets = rng.uniform(-1, 1, (count, 3))
    directions = (targets - origins) * rng.uniform(0.5, 2.0, (count, 1))  # not unit length on purpose
    return origins.astype(np.float32), directions.astype(np.float32)
