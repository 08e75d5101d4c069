"""vkas: watertight, deterministic ray casting on numpy arrays.

The Python binding of vkas, an implementation of Vulkan's acceleration-structure host commands and host ray queries
on the CPU. Rays through shared edges and vertices hit exactly once (the specification's watertight test), and
results are bit-identical whatever the number of threads. See docs/PYTHON.md.

    import numpy as np, vkas
    dev = vkas.Device()
    scene = vkas.Scene(dev, vertices, faces)
    hits = scene.intersect(origins, directions)      # hits.t: inf on a miss
"""

import enum
import numbers
import threading

import numpy as np

from . import _core
from ._errors import ValidationError

__version__ = "0.1.0"

__all__ = [
    "BottomLevel",
    "Device",
    "Hits",
    "Instance",
    "InstanceFlags",
    "RayFlags",
    "Scene",
    "Spheres",
    "TopLevel",
    "Triangles",
    "ValidationError",
]


class RayFlags(enum.IntFlag):
    """Ray flags: the SPIR-V ``RayFlags`` values (``VKAS_RAY_FLAG_*`` in vkas.h)."""

    NoneKHR = 0x0
    OpaqueKHR = 0x1
    NoOpaqueKHR = 0x2
    TerminateOnFirstHitKHR = 0x4
    SkipClosestHitShaderKHR = 0x8
    CullBackFacingTrianglesKHR = 0x10
    CullFrontFacingTrianglesKHR = 0x20
    CullOpaqueKHR = 0x40
    CullNoOpaqueKHR = 0x80
    SkipTrianglesKHR = 0x100
    SkipAABBsKHR = 0x200
    ForceOpacityMicromap2StateEXT = 0x400


class InstanceFlags(enum.IntFlag):
    """Instance flags: ``VkGeometryInstanceFlagBitsKHR`` (``VK_GEOMETRY_INSTANCE_<NAME>_BIT_KHR``)."""

    NONE = 0x0
    TRIANGLE_FACING_CULL_DISABLE = 0x1
    TRIANGLE_FLIP_FACING = 0x2
    FORCE_OPAQUE = 0x4
    FORCE_NO_OPAQUE = 0x8
    FORCE_OPACITY_MICROMAP_2_STATE = 0x10
    DISABLE_OPACITY_MICROMAPS = 0x20


_KNOWN_RAY_FLAGS = 0x7FF
_OPAQUE_GROUP = RayFlags.OpaqueKHR | RayFlags.NoOpaqueKHR | RayFlags.CullOpaqueKHR | RayFlags.CullNoOpaqueKHR
_TRIANGLE_GROUP = (RayFlags.SkipTrianglesKHR | RayFlags.CullBackFacingTrianglesKHR
                   | RayFlags.CullFrontFacingTrianglesKHR)

# VkBuildAccelerationStructureFlagBitsKHR
_ALLOW_UPDATE = 0x1
_ALLOW_COMPACTION = 0x2
_PREFER_FAST_TRACE = 0x4
_PREFER_FAST_BUILD = 0x8
_MOTION = 0x20
_PREFERENCES = {"default": 0, "fast_trace": _PREFER_FAST_TRACE, "fast_build": _PREFER_FAST_BUILD}

# VkGeometryTypeKHR, as the block's header and geometry table record them
_GEOMETRY_KINDS = {0: "triangles", 1: "aabbs", 2: "instances", 1000429004: "spheres", 1000429005: "lss"}

# VkAccelerationStructureInstanceKHR
_INSTANCE_DTYPE = np.dtype([("transform", "<f4", (3, 4)), ("custom_mask", "<u4"), ("sbt_flags", "<u4"),
                            ("reference", "<u8")])
assert _INSTANCE_DTYPE.itemsize == 64

_IDENTITY = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], dtype=np.float32)


# ---------------------------------------------------------------------------------------------------------------
# Argument checks. The rule: float32 arrays are read in place, so they must be C-contiguous (a float32 array that is
# not raises ValueError: pass np.ascontiguousarray(a)); float64 arrays (and array-likes such as lists of floats)
# are converted to float32 once, whatever their layout. Any other dtype is a TypeError.

def _shape_text(shape):
    return "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _an(desc):
    return ("an " if desc[:1] in "(aeiou" and not desc.startswith("(3") else "a ") + desc


def _float32(value, name, desc, shape_ok):
    """value as a C-contiguous float32 array; desc like '(R, 3)' for the messages; shape_ok(shape) -> bool."""
    try:
        a = np.asarray(value)
    except Exception as e:  # numpy raises for ragged lists and exotic objects
        raise TypeError(f"{name}: expected {_an(desc)} float32 array, got {type(value).__name__} that numpy cannot "
                        f"read as an array ({e})") from e
    if a.dtype == np.float32:
        if not shape_ok(a.shape):
            raise ValueError(f"{name}: expected {_an(desc)} float32 array, got shape {_shape_text(a.shape)}")
        if not a.flags.c_contiguous:
            raise ValueError(f"{name}: the float32 array is not C-contiguous; vkas reads float32 arrays in place "
                             f"and does not copy them behind your back: pass np.ascontiguousarray({name})")
        if not a.flags.aligned:
            raise ValueError(f"{name}: the float32 array is not aligned to 4 bytes; vkas reads float32 arrays in "
                             f"place and does not copy them behind your back: pass np.require({name}, "
                             f"requirements='CA')")
        return a
    if a.dtype == np.float64:
        if not shape_ok(a.shape):
            raise ValueError(f"{name}: expected {_an(desc)} float32 array, got shape {_shape_text(a.shape)}")
        with np.errstate(over="ignore"):
            return np.ascontiguousarray(a, dtype=np.float32)
    raise TypeError(f"{name}: expected {_an(desc)} float32 array (float64 is converted), got dtype {a.dtype}"
                    + (f" ({type(value).__name__})" if not isinstance(value, np.ndarray) else ""))


def _rows3(shape):
    return len(shape) == 2 and shape[1] == 3


def _first_bad(mask):
    return int(np.flatnonzero(mask)[0])


def _check_finite(a, name, what="values"):
    ok = np.isfinite(a)
    if not ok.all():
        i = np.unravel_index(_first_bad(~ok.ravel()), a.shape)
        where = f"[{', '.join(str(int(k)) for k in i)}]"
        raise ValueError(f"{name}: {what} must be finite, {name}{where} is {a[i]}")


def _bool(value, name):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(f"{name}: expected a bool, got {type(value).__name__}")


def _int(value, name, lo, hi):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an int, got {type(value).__name__}")
    v = int(value)
    if not lo <= v <= hi:
        raise ValueError(f"{name}: must be in [{lo}, {hi if hi < 4096 else hex(hi)}], got {v}")
    return v


def _transform(value, name):
    """(3, 4) row-major affine transform (a (4, 4) one with last row 0 0 0 1 is accepted), or None."""
    if value is None:
        return None
    t = _float32(value, name, "(3, 4)", lambda s: s in ((3, 4), (4, 4)))
    _check_finite(t, name)
    if t.shape == (4, 4):
        if not np.array_equal(t[3], np.array([0, 0, 0, 1], dtype=np.float32)):
            raise ValueError(f"{name}: a (4, 4) transform must be affine (last row 0 0 0 1), got {t[3].tolist()}")
        t = np.ascontiguousarray(t[:3])
    return t


def _indices(value, nvertices):
    try:
        a = np.asarray(value)
    except Exception as e:  # pragma: no cover
        raise TypeError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got {type(value).__name__}") from e
    if a.dtype == np.bool_ or not np.issubdtype(a.dtype, np.integer):
        raise TypeError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got dtype {a.dtype}")
    if not _rows3(a.shape):
        raise ValueError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got shape {_shape_text(a.shape)}")
    if a.size:
        lo, hi = int(a.min()), int(a.max())
        if lo < 0 or hi >= nvertices:
            bad = (a < 0) | (a >= nvertices)
            face = _first_bad(bad.any(axis=1))
            raise ValueError(f"indices: face {face} is {a[face].tolist()}, out of range for {nvertices} vertices")
    if a.dtype in (np.uint16, np.uint32) and a.dtype.isnative:
        if not a.flags.c_contiguous:
            raise ValueError("indices: the array is not C-contiguous; vkas reads uint16/uint32 indices in place: "
                             "pass np.ascontiguousarray(indices)")
        if not a.flags.aligned:
            raise ValueError(f"indices: the {a.dtype} array is not aligned to {a.dtype.itemsize} bytes; vkas reads "
                             "uint16/uint32 indices in place: pass np.require(indices, requirements='CA')")
        return a
    return np.ascontiguousarray(a, dtype=np.uint32)  # int32, int64, ...: range checked above


# ---------------------------------------------------------------------------------------------------------------
# Geometry

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


def _build_flags(preference, allow_update, allow_compaction):
    if not isinstance(preference, str) or preference not in _PREFERENCES:
        raise ValueError(f"preference: expected one of {', '.join(map(repr, _PREFERENCES))}, got {preference!r}")
    return (_PREFERENCES[preference] | (_ALLOW_UPDATE if _bool(allow_update, "allow_update") else 0)
            | (_ALLOW_COMPACTION if _bool(allow_compaction, "allow_compaction") else 0))


def _preference_of(flags):
    return "fast_trace" if flags & _PREFER_FAST_TRACE else "fast_build" if flags & _PREFER_FAST_BUILD else "default"


# ---------------------------------------------------------------------------------------------------------------
# Device

class Device:
    """A vkas device.

    validation: vkas checks every valid-usage rule of every command it runs and reports a broken one, which the
    package raises as vkas.ValidationError (with validation=False those checks are off and invalid usage is
    undefined, as in Vulkan without layers; the package's own argument checks stay on).
    threads: the threads of batch calls (intersect, occluded, intersect_all, large builds); 0 = all cores.
    Results do not depend on it.
    """

    def __init__(self, validation=True, threads=0):
        self._core = _core.Device(_bool(validation, "validation"), _int(threads, "threads", 0, 4096))

    @property
    def validation(self):
        return self._core.validation

    @property
    def threads(self):
        """The number of threads batch calls use (threads=0 resolved to the number of cores)."""
        return self._core.threads

    def __repr__(self):
        return f"vkas.Device(validation={self.validation}, threads={self._core.requested_threads})"

    def __reduce__(self):
        return (Device, (self.validation, self._core.requested_threads))

    def build_bottom_level(self, geometries, preference="default", allow_update=False, allow_compaction=False):
        """Builds a bottom level of triangles or spheres (a list of vkas.Triangles or of vkas.Spheres)."""
        geoms = _geometries(geometries)
        flags = _build_flags(preference, allow_update, allow_compaction)
        return BottomLevel._wrap(self, self._core.build_bottom([g._spec() for g in geoms], flags))

    def build_top_level(self, instances, preference="default", allow_update=False, allow_compaction=False):
        """Builds a top level over a list of vkas.Instance (None: an inactive instance, which keeps its id)."""
        inst = _instances(self, instances)
        flags = _build_flags(preference, allow_update, allow_compaction)
        return TopLevel._wrap(self, self._core.build_top(_records(inst), flags), inst)

    def deserialize(self, blob, bottom_levels=None):
        """Loads a serialized structure (bytes from serialize()) into this device.

        A top level refers to its bottom levels: give bottom_levels, one vkas.BottomLevel per instance in instance
        order (None for an inactive one), e.g. deserialized copies of tlas.bottom_levels. They must hold the same
        geometry as the bottom levels the top level was built with (a clone, a compacted or deserialized copy):
        the instance boxes come from the serialized data. The blob is checked completely (integrity hash,
        structure) before it is used: a damaged one raises ValueError, or vkas.ValidationError with validation on.
        """
        if isinstance(blob, np.ndarray):
            if blob.dtype != np.uint8 or not blob.flags.c_contiguous:
                raise TypeError("blob: expected bytes (or a C-contiguous uint8 array)")
        elif isinstance(blob, memoryview):
            if not blob.c_contiguous:
                raise ValueError("blob: the memoryview is not C-contiguous: pass bytes(blob)")
        elif not isinstance(blob, (bytes, bytearray)):
            raise TypeError(f"blob: expected bytes, got {type(blob).__name__}")
        if bottom_levels is None:
            bottoms, replace = [], False
        else:
            if not isinstance(bottom_levels, (list, tuple)):
                raise TypeError(f"bottom_levels: expected a list of vkas.BottomLevel, got "
                                f"{type(bottom_levels).__name__}")
            for i, b in enumerate(bottom_levels):
                if b is not None and not isinstance(b, BottomLevel):
                    raise TypeError(f"bottom_levels[{i}]: expected vkas.BottomLevel or None, got {type(b).__name__}")
                if b is not None and b.device is not self:
                    raise ValueError(f"bottom_levels[{i}]: belongs to another vkas.Device")
            bottoms, replace = [b._s if b is not None else None for b in bottom_levels], True
        s = self._core.deserialize(blob, bottoms, replace)
        if s.type == 1:
            return BottomLevel._wrap(self, s)
        if s.build_flags & _MOTION:
            raise ValueError("blob: a motion top level (VK_NV_ray_tracing_motion_blur) is not supported here")
        return TopLevel._wrap(self, s, _instances_from_records(s, list(bottom_levels or [])))


def _check_device(obj, device, name):
    if obj.device is not device:
        raise ValueError(f"{name}: belongs to another vkas.Device")


# ---------------------------------------------------------------------------------------------------------------
# Structures

class _Structure:
    __slots__ = ("device", "_s", "__weakref__")

    @property
    def allow_update(self):
        return bool(self._s.build_flags & _ALLOW_UPDATE)

    @property
    def allow_compaction(self):
        return bool(self._s.build_flags & _ALLOW_COMPACTION)

    @property
    def preference(self):
        return _preference_of(self._s.build_flags)

    @property
    def size(self):
        """Bytes the structure uses (what a compacted copy or a clone needs)."""
        return int(self._s.used_size)

    @property
    def allocated_size(self):
        """Bytes allocated for it (the build-size query's bound; the used size for a copy)."""
        return int(self._s.size)

    def _u32(self, offset):
        return int(np.frombuffer(self._s.read(offset, 4), dtype="<u4")[0])

    @property
    def geometry_count(self):
        return self._u32(56)

    @property
    def primitive_count(self):
        """Primitives (or instances) given to the last build, inactive ones included."""
        return self._u32(60)

    def serialize(self):
        """The serialized form (bytes; docs/FORMAT.md, "Serialized form"): give it to Device.deserialize."""
        return self.device._core.serialize(self._s)

    def _copy_checks(self):
        if not self.allow_compaction:
            raise ValidationError(
                "VUID-VkCopyAccelerationStructureInfoKHR-src-03411",
                "compact(): the structure was not built with allow_compaction=True "
                "(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR)")


class BottomLevel(_Structure):
    """A bottom-level acceleration structure (Device.build_bottom_level, compact, deserialize)."""

    __slots__ = ("_generation",)

    def __init__(self):
        raise TypeError("vkas.BottomLevel: use Device.build_bottom_level or Device.deserialize")

    @classmethod
    def _wrap(cls, device, s):
        self = object.__new__(cls)
        self.device, self._s, self._generation = device, s, 0
        return self

    @property
    def kind(self):
        """'triangles', 'spheres' (or 'aabbs' / 'lss' for structures built through the C API)."""
        return _GEOMETRY_KINDS.get(self._u32(96), "unknown")

    def _geometry_table(self):
        n = self.geometry_count
        offset = int(np.frombuffer(self._s.read(72, 8), dtype="<u8")[0])
        return np.frombuffer(self._s.read(offset, 32 * n), dtype="<u4").reshape(n, 8) if n else np.zeros((0, 8))

    def update(self, geometries):
        """Refits the structure in place to new positions (same topology: geometry count and kinds, primitive
        counts, index values). Needs allow_update=True. Top levels using it refit themselves at their next trace."""
        geoms = _geometries(geometries)
        if not self.allow_update:
            raise ValidationError(
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667",
                "update(): the bottom level was not built with allow_update=True "
                "(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR)")
        table = self._geometry_table()
        if len(geoms) != len(table):
            raise ValidationError(
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03758",
                f"update(): {len(geoms)} geometries, the last build had {len(table)}")
        for i, (g, row) in enumerate(zip(geoms, table)):
            if _GEOMETRY_KINDS.get(int(row[0])) != g.kind:
                raise ValidationError(
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-03761",
                    f"update(): geometries[{i}] is {g.kind}, the last build had "
                    f"{_GEOMETRY_KINDS.get(int(row[0]), 'unknown')}")
            if g.primitive_count != int(row[2]):
                raise ValidationError(
                    "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769",
                    f"update(): geometries[{i}] has {g.primitive_count} primitives, the last build had {int(row[2])}")
        self.device._core.update_bottom(self._s, [g._spec() for g in geoms], self._s.build_flags)
        self._generation += 1

    def compact(self):
        """A compacted copy (exactly the bytes the structure uses). Needs allow_compaction=True."""
        self._copy_checks()
        return BottomLevel._wrap(self.device, self.device._core.copy(self._s, True))

    def clone(self):
        """A copy of the structure (same bytes, same build flags)."""
        return BottomLevel._wrap(self.device, self.device._core.copy(self._s, False))

    def __reduce__(self):
        return (_load_bottom, (self.device, self.serialize()))

    def __repr__(self):
        return (f"vkas.BottomLevel({self.kind}, {self.geometry_count} geometries, {self.primitive_count} primitives, "
                f"{self.size} bytes)")


def _load_bottom(device, blob):
    return device.deserialize(blob)


class Instance:
    """An instance of a bottom level in a top level.

    transform: (3, 4) row-major object-to-world transform (float32, float64 converted; a (4, 4) affine one is
    accepted), None for the identity. mask: 8 bits, tested against the ray's mask. custom_index: 24 bits, reported
    as hits.custom_index. flags: vkas.InstanceFlags. sbt_offset: the 24-bit shader binding table record offset.
    """

    __slots__ = ("bottom_level", "transform", "mask", "custom_index", "flags", "sbt_offset")

    def __init__(self, blas, transform=None, mask=0xFF, custom_index=0, flags=0, sbt_offset=0):
        if not isinstance(blas, BottomLevel):
            raise TypeError(f"blas: expected a vkas.BottomLevel, got {type(blas).__name__}")
        self.bottom_level = blas
        t = _transform(transform, "transform")
        self.transform = _IDENTITY.copy() if t is None else t
        self.mask = _int(mask, "mask", 0, 0xFF)
        self.custom_index = _int(custom_index, "custom_index", 0, 0xFFFFFF)
        self.flags = InstanceFlags(_int(flags, "flags", 0, 0xFF))
        if self.flags & ~0x3F:
            raise ValueError(f"flags: unknown instance flag bits {int(self.flags) & ~0x3F:#x}")
        self.sbt_offset = _int(sbt_offset, "sbt_offset", 0, 0xFFFFFF)

    @property
    def blas(self):
        return self.bottom_level

    def __getstate__(self):
        return {k: getattr(self, k) for k in self.__slots__}

    def __setstate__(self, state):
        for k, v in state.items():
            object.__setattr__(self, k, v)

    def __repr__(self):
        return (f"vkas.Instance({self.bottom_level!r}, mask={self.mask:#x}, custom_index={self.custom_index}, "
                f"flags={int(self.flags):#x})")


def _instances(device, instances):
    if isinstance(instances, Instance):
        instances = [instances]
    if not isinstance(instances, (list, tuple)):
        raise TypeError(f"instances: expected a list of vkas.Instance, got {type(instances).__name__}")
    out = []
    for i, inst in enumerate(instances):
        if isinstance(inst, BottomLevel):
            inst = Instance(inst)
        if inst is not None and not isinstance(inst, Instance):
            raise TypeError(f"instances[{i}]: expected a vkas.Instance (or None), got {type(inst).__name__}")
        if inst is not None and inst.bottom_level.device is not device:
            raise ValueError(f"instances[{i}]: its bottom level belongs to another vkas.Device")
        out.append(inst)
    if len(out) >= 2**24:
        raise ValueError("instances: at most 2**24 - 1 instances")
    return out


def _records(instances):
    rec = np.zeros(len(instances), dtype=_INSTANCE_DTYPE)
    for k, inst in enumerate(instances):
        if inst is None:
            continue  # inactive: reference 0
        rec[k]["transform"] = inst.transform
        rec[k]["custom_mask"] = inst.custom_index | (inst.mask << 24)
        rec[k]["sbt_flags"] = inst.sbt_offset | (int(inst.flags) << 24)
        rec[k]["reference"] = inst.bottom_level._s.handle
    return rec


def _instances_from_records(s, bottom_levels):
    """The Instance list of a deserialized top level, from its instance records (docs/FORMAT.md, InstanceRecord)."""
    n = len(bottom_levels)
    out = [None] * n
    count = int(np.frombuffer(s.read(64, 4), dtype="<u4")[0])
    offset = int(np.frombuffer(s.read(88, 8), dtype="<u8")[0])
    if count == 0:
        return out
    raw = s.read(offset, 128 * count)
    rec = np.frombuffer(raw, dtype=np.uint8).reshape(count, 128)
    for r in rec:
        words = r[96:116].view("<u4")
        iid = int(words[4])
        blas = bottom_levels[iid] if iid < n else None
        if blas is None:
            continue
        inst = Instance(blas, np.array(r[0:48].view("<f4").reshape(3, 4)),
                        mask=int(words[0]) >> 24, custom_index=int(words[0]) & 0xFFFFFF,
                        flags=(int(words[1]) >> 24) & 0x3F, sbt_offset=int(words[1]) & 0xFFFFFF)
        out[iid] = inst
    return out


class TopLevel(_Structure):
    """A top-level acceleration structure: what rays are traced through."""

    __slots__ = ("_instances", "_generations", "_lock")

    def __init__(self):
        raise TypeError("vkas.TopLevel: use Device.build_top_level or Device.deserialize")

    @classmethod
    def _wrap(cls, device, s, instances):
        self = object.__new__(cls)
        self.device, self._s, self._instances = device, s, list(instances)
        self._lock = threading.Lock()
        self._generations = self._current_generations()
        return self

    def _current_generations(self):
        seen = {}
        for inst in self._instances:
            if inst is not None:
                seen[id(inst.bottom_level)] = (inst.bottom_level, inst.bottom_level._generation)
        return list(seen.values())

    @property
    def instances(self):
        """The instances, in instance-id order (None for an inactive one)."""
        return list(self._instances)

    @property
    def bottom_levels(self):
        """The bottom level of each instance, in instance-id order (None for an inactive one)."""
        return [None if i is None else i.bottom_level for i in self._instances]

    def _refresh(self):
        # A bottom level updated after this top level was built: refit (or rebuild) it first, so that rays never
        # meet stale instance boxes.
        if all(b._generation == g for b, g in self._generations):
            return
        with self._lock:
            if all(b._generation == g for b, g in self._generations):
                return
            rec = _records(self._instances)
            if self.allow_update:
                self.device._core.update_top(self._s, rec, self._s.build_flags)
            else:
                self._s = self.device._core.build_top(rec, self._s.build_flags)
            self._generations = self._current_generations()

    def update(self, instances):
        """Refits the top level to new instances (same count; transforms, masks, flags and bottom levels may
        change). Needs allow_update=True."""
        inst = _instances(self.device, instances)
        if not self.allow_update:
            raise ValidationError(
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667",
                "update(): the top level was not built with allow_update=True "
                "(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR)")
        if len(inst) != self.primitive_count:
            raise ValidationError(
                "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769",
                f"update(): {len(inst)} instances, the last build had {self.primitive_count}")
        with self._lock:
            self.device._core.update_top(self._s, _records(inst), self._s.build_flags)
            self._instances = inst
            self._generations = self._current_generations()

    def compact(self):
        """A compacted copy (same instances). Needs allow_compaction=True."""
        self._refresh()
        self._copy_checks()
        return TopLevel._wrap(self.device, self.device._core.copy(self._s, True), self._instances)

    def clone(self):
        self._refresh()
        return TopLevel._wrap(self.device, self.device._core.copy(self._s, False), self._instances)

    def serialize(self):
        """The serialized form. Its handle array names the bottom levels by address: to load it, give
        Device.deserialize the bottom levels again (pickle does all of this)."""
        self._refresh()
        return super().serialize()

    def __reduce__(self):
        return (_load_top, (self.device, self.serialize(), self._instances))

    def __repr__(self):
        return f"vkas.TopLevel({self.primitive_count} instances, {self.size} bytes)"

    # -- tracing ------------------------------------------------------------------------------------------------

    def _rays(self, origins, directions, tmin, tmax, flags, mask):
        o = _float32(origins, "origins", "(R, 3)", _rows3)
        d = _float32(directions, "directions", f"(R, 3)", _rows3)
        if d.shape != o.shape:
            raise ValueError(f"directions: expected an (R, 3) float32 array with R = {len(o)} (as origins), got "
                             f"shape {_shape_text(d.shape)}")
        t0 = _t(tmin, "tmin", len(o))
        t1 = _t(tmax, "tmax", len(o))
        flags = _ray_flags(flags)
        mask = _int(mask, "mask", 0, 0xFF)
        return o, d, t0, t1, flags, mask

    def _check_flags(self, flags, mask):
        if not self.device.validation:  # vkas checks them itself with validation on
            _flag_rules(flags)

    def intersect(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF):
        """The closest hit of each ray (vkasTraceRays, closest-hit mode): a vkas.Hits of R entries.

        origins, directions: (R, 3) float32 (float64 converted); directions are not normalised (t is in units of
        the direction's length). tmin, tmax: numbers or (R,) arrays. flags: vkas.RayFlags. mask: the ray's 8-bit
        cull mask, tested against each instance's mask."""
        o, d, t0, t1, flags, mask = self._rays(origins, directions, tmin, tmax, flags, mask)
        self._check_flags(flags, mask)
        self._refresh()
        return Hits(*self.device._core.trace(self._s, o, d, t0, t1, flags, mask, False))

    def occluded(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF):
        """Whether each ray hits anything in (tmin, tmax) (vkasTraceRays, any-hit mode): (R,) bool."""
        o, d, t0, t1, flags, mask = self._rays(origins, directions, tmin, tmax, flags, mask)
        self._check_flags(flags, mask)
        self._refresh()
        return self.device._core.trace(self._s, o, d, t0, t1, flags, mask, True)

    def intersect_all(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF, max_hits=None):
        """Every hit along each ray, ordered by ray, then by t (ties: instance, geometry, primitive id).

        Returns (ray_index, hits): ray_index (H,) int64, the ray of each hit; hits a vkas.Hits of H entries.
        Every primitive the ray meets in (tmin, tmax) counts once, opaque or not (a ray query with NoOpaqueKHR
        whose candidates are collected and none confirmed): the opacity flags (OpaqueKHR, CullOpaqueKHR,
        CullNoOpaqueKHR) and TerminateOnFirstHitKHR do not apply and raise ValueError; culling, skip flags and
        masks do. max_hits: keep at most that many hits a ray (the closest ones), None for all."""
        o, d, t0, t1, flags, mask = self._rays(origins, directions, tmin, tmax, flags, mask)
        bad = flags & (RayFlags.OpaqueKHR | RayFlags.CullOpaqueKHR | RayFlags.CullNoOpaqueKHR
                       | RayFlags.TerminateOnFirstHitKHR)
        if bad:
            raise ValueError(f"flags: intersect_all reports every hit, opaque or not: {RayFlags(bad)!r} does not "
                             f"apply (use intersect or occluded)")
        limit = 0 if max_hits is None else _int(max_hits, "max_hits", 1, 2**32 - 1)
        flags |= RayFlags.NoOpaqueKHR
        self._check_flags(flags, mask)
        self._refresh()
        ray, *fields = self.device._core.trace_all(self._s, o, d, t0, t1, int(flags), mask, limit)
        return ray, Hits(*fields)


def _load_top(device, blob, instances):
    return device.deserialize(blob, [None if i is None else i.bottom_level for i in instances])


def _ndim(value, name, desc):
    """np.ndim(value), or TypeError naming the argument where numpy cannot make an array of it (ragged lists)."""
    try:
        return np.ndim(value)
    except Exception as e:
        raise TypeError(f"{name}: expected {desc}, got {type(value).__name__} that numpy cannot read as an array "
                        f"({e})") from e


def _t(value, name, count):
    if _ndim(value, name, "a number or an (R,) float32 array") == 0:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray)):
            raise TypeError(f"{name}: expected a number or an (R,) float32 array, got {type(value).__name__}")
        if isinstance(value, np.ndarray) and not np.issubdtype(value.dtype, np.floating) \
                and not np.issubdtype(value.dtype, np.integer):
            raise TypeError(f"{name}: expected a number or an (R,) float32 array, got dtype {value.dtype}")
        with np.errstate(over="ignore"):
            return np.array(value, dtype=np.float32)
    return _float32(value, name, f"(R,) (R = {count})", lambda s: s == (count,))


def _ray_flags(flags):
    f = _int(flags, "flags", 0, 2**32 - 1)
    if f & ~_KNOWN_RAY_FLAGS:
        raise ValueError(f"flags: unknown ray flag bits {f & ~_KNOWN_RAY_FLAGS:#x} (see vkas.RayFlags)")
    return RayFlags(f)


def _flag_rules(flags):
    """The ray-flag rules of OpRayQueryInitializeKHR, checked here when the device's validation is off."""
    def one(bits):
        return bits & (bits - 1) == 0
    if not one(int(flags & _OPAQUE_GROUP)):
        raise ValidationError("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06891",
                              f"flags {int(flags):#x} has more than one of OpaqueKHR, NoOpaqueKHR, CullOpaqueKHR "
                              f"and CullNoOpaqueKHR")
    if not one(int(flags & _TRIANGLE_GROUP)):
        raise ValidationError("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06890",
                              f"flags {int(flags):#x} has more than one of SkipTrianglesKHR, "
                              f"CullBackFacingTrianglesKHR and CullFrontFacingTrianglesKHR")
    if flags & RayFlags.SkipTrianglesKHR and flags & RayFlags.SkipAABBsKHR:
        raise ValidationError("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06889",
                              f"flags {int(flags):#x} has both SkipTrianglesKHR and SkipAABBsKHR")


class Hits:
    """Hits of a batch of rays, one entry per ray (intersect) or per hit (intersect_all).

    t (float32, inf on a miss), primitive_id, geometry_index, instance_id, custom_index (int32, -1 on a miss),
    barycentrics (n, 2) float32 (0 on a miss and for spheres), front_face (bool; False on a miss and for spheres).
    """

    __slots__ = ("t", "primitive_id", "geometry_index", "instance_id", "custom_index", "barycentrics", "front_face")

    def __init__(self, t, primitive_id, geometry_index, instance_id, custom_index, barycentrics, front_face):
        self.t = t
        self.primitive_id = primitive_id
        self.geometry_index = geometry_index
        self.instance_id = instance_id
        self.custom_index = custom_index
        self.barycentrics = barycentrics
        self.front_face = front_face

    @property
    def hit(self):
        """(n,) bool: True where there is a hit."""
        return self.primitive_id >= 0

    def __len__(self):
        return len(self.t)

    def __getitem__(self, index):
        return Hits(*(getattr(self, k)[index] for k in self.__slots__))

    def __eq__(self, other):
        return isinstance(other, Hits) and all(
            np.array_equal(getattr(self, k), getattr(other, k)) for k in self.__slots__)

    __hash__ = None

    def __repr__(self):
        return f"vkas.Hits({len(self)} entries, {int(np.count_nonzero(self.hit))} hits)"


class Scene:
    """One mesh, one bottom level, one identity instance: Scene(dev, vertices, indices).

    vertices and indices as for vkas.Triangles; the build options as for Device.build_bottom_level. Traces like a
    TopLevel (intersect, occluded, intersect_all). Pickles through the serialized form, its bottom level with it.
    """

    __slots__ = ("device", "bottom_level", "top_level")

    def __init__(self, device, vertices, indices=None, preference="fast_trace", allow_update=False,
                 allow_compaction=False, opaque=True):
        if not isinstance(device, Device):
            raise TypeError(f"device: expected a vkas.Device, got {type(device).__name__}")
        self.device = device
        self.bottom_level = device.build_bottom_level([Triangles(vertices, indices, opaque=opaque)], preference,
                                                      allow_update, allow_compaction)
        self.top_level = device.build_top_level([Instance(self.bottom_level)])

    @classmethod
    def _from_top_level(cls, top_level):
        self = object.__new__(cls)
        self.device, self.top_level = top_level.device, top_level
        self.bottom_level = top_level.instances[0].bottom_level
        return self

    def intersect(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF):
        return self.top_level.intersect(origins, directions, tmin, tmax, flags, mask)

    def occluded(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF):
        return self.top_level.occluded(origins, directions, tmin, tmax, flags, mask)

    def intersect_all(self, origins, directions, tmin=0.0, tmax=np.inf, flags=0, mask=0xFF, max_hits=None):
        return self.top_level.intersect_all(origins, directions, tmin, tmax, flags, mask, max_hits)

    intersect.__doc__ = TopLevel.intersect.__doc__
    occluded.__doc__ = TopLevel.occluded.__doc__
    intersect_all.__doc__ = TopLevel.intersect_all.__doc__

    def __reduce__(self):
        return (Scene._from_top_level, (self.top_level,))

    def __repr__(self):
        return f"vkas.Scene({self.bottom_level!r})"
