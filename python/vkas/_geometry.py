"""The geometries of a bottom level: Triangles and Spheres, and the geometry-list check of builds and updates."""

import numbers

import numpy as np

from ._checks import _bool, _check_finite, _first_bad, _float32, _indices, _ndim, _rows3, _transform
from ._errors import ValidationError


class Triangles:
    """A triangle geometry of a bottom level.

    vertices: (N, 3) float32 (read in place) or float64 (converted once to float32). A vertex whose x is NaN marks
    the triangles using it inactive (Vulkan's rule: never hit, still counted in primitive ids); every other
    coordinate must be finite.
    indices: (M, 3) uint16 or uint32 (read in place), int32 or another integer type (range-checked, converted once
    to uint32), or None for a triangle soup of N/3 triangles.
    transform: (3, 4) row-major affine transform applied to the vertices (in double precision, by vkas), or None.
    opaque: the geometry's OPAQUE flag (the opacity ray flags act on it).
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

    def __init__(self, vertices, indices=None, transform=None, opaque=True):
        v = _float32(vertices, "vertices", "(N, 3)", _rows3)
        bad = ~np.isfinite(v)
        if bad.any():
            rows = bad.any(axis=1) & ~np.isnan(v[:, 0])
            if rows.any():
                r = _first_bad(rows)
                raise ValueError(f"vertices: must be finite (a NaN x marks an inactive vertex), vertices[{r}] is "
                                 f"{v[r].tolist()}")
        if indices is None:
            if len(v) % 3:
                raise ValueError(f"vertices: a triangle soup (indices=None) needs a multiple of 3 vertices, "
                                 f"got {len(v)}")
            idx = None
        else:
            idx = _indices(indices, len(v))
        if len(v) >= 2**32:
            raise ValueError("vertices: at most 2**32 - 1 vertices")
        self.vertices = v
        self.indices = idx
        self.transform = _transform(transform, "transform")
        self.opaque = _bool(opaque, "opaque")

    kind = "triangles"

    @property
    def primitive_count(self):
        return len(self.indices) if self.indices is not None else len(self.vertices) // 3

    def _spec(self):
        return (0, self.vertices, self.indices, self.transform, self.opaque)

    def __repr__(self):
        return (f"vkas.Triangles({self.primitive_count} triangles, {len(self.vertices)} vertices"
                f"{', transform' if self.transform is not None else ''}{'' if self.opaque else ', not opaque'})")


class Spheres:
    """A sphere geometry of a bottom level (VK_NV_ray_tracing_linear_swept_spheres).

    centers: (N, 3) float32 (float64 converted); radii: (N,) float32 (float64 converted) or one number for all.
    Centers and radii must be finite, radii >= 0 (a radius of 0 is never hit).
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

    kind = "spheres"

    def __init__(self, centers, radii, opaque=True):
        c = _float32(centers, "centers", "(N, 3)", _rows3)
        _check_finite(c, "centers")
        if _ndim(radii, "radii", "a number or an (N,) float32 array") == 0 and isinstance(radii, numbers.Real) and not isinstance(radii, (bool, np.bool_)):
            r = np.full(len(c), radii, dtype=np.float32)
        else:
            r = _float32(radii, "radii", f"(N,) (N = {len(c)})", lambda s: s == (len(c),))
        _check_finite(r, "radii")
        if (r < 0).any():
            i = _first_bad(r < 0)
            raise ValueError(f"radii: must be >= 0, radii[{i}] is {r[i]}")
        self.centers = c
        self.radii = r
        self.opaque = _bool(opaque, "opaque")

    @property
    def primitive_count(self):
        return len(self.centers)

    def _spec(self):
        return (1, self.centers, self.radii, self.opaque)

    def __repr__(self):
        return f"vkas.Spheres({len(self.centers)} spheres{'' if self.opaque else ', not opaque'})"


def _geometries(geometries):
    if isinstance(geometries, (Triangles, Spheres)):
        geometries = [geometries]
    if not isinstance(geometries, (list, tuple)):
        raise TypeError(f"geometries: expected a list of vkas.Triangles or vkas.Spheres, "
                        f"got {type(geometries).__name__}")
    for i, g in enumerate(geometries):
        if not isinstance(g, (Triangles, Spheres)):
            raise TypeError(f"geometries[{i}]: expected vkas.Triangles or vkas.Spheres, got {type(g).__name__}")
    kinds = {g.kind for g in geometries}
    if len(kinds) > 1:
        raise ValidationError(
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03792",
            "geometries: a bottom level holds one geometry type: triangles or spheres, not both (build one bottom "
            "level per type and instance both)")
    return list(geometries)
