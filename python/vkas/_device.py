"""Device: the vkas device, with the builds (build_bottom_level, build_top_level) and deserialize."""

import numpy as np

from . import _core
from ._checks import _bool, _int
from ._flags import _MOTION, _build_flags
from ._geometry import _geometries
from ._structures import BottomLevel, _instances, _instances_from_records, _records
from ._top_level import TopLevel


class Device:
    """A vkas device.

    validation: vkas checks every valid-usage rule of every command it runs and reports a broken one, which the
    package raises as vkas.ValidationError (with validation=False those checks are off and invalid usage is
    undefined, as in Vulkan without layers; the package's own argument checks stay on).
    threads: the threads of batch calls (intersect, occluded, intersect_all, large builds); 0 = all cores.
    Results do not depend on it.
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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
