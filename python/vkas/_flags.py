"""RayFlags and InstanceFlags, the Vulkan flag bits, geometry kinds and instance record the vkas package writes and
reads, and the checks of the build and ray flag arguments."""

import enum

import numpy as np

from ._checks import _bool, _int
from ._errors import ValidationError


class RayFlags(enum.IntFlag):
    """Ray flags: the SPIR-V ``RayFlags`` values (``VKAS_RAY_FLAG_*`` in vkas.h)."""

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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


def _build_flags(preference, allow_update, allow_compaction):
    if not isinstance(preference, str) or preference not in _PREFERENCES:
        raise ValueError(f"preference: expected one of {', '.join(map(repr, _PREFERENCES))}, got {preference!r}")
    return (_PREFERENCES[preference] | (_ALLOW_UPDATE if _bool(allow_update, "allow_update") else 0)
            | (_ALLOW_COMPACTION if _bool(allow_compaction, "allow_compaction") else 0))


def _preference_of(flags):
    return "fast_trace" if flags & _PREFER_FAST_TRACE else "fast_build" if flags & _PREFER_FAST_BUILD else "default"


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
