"""Scene: one mesh, one bottom level, one identity instance, traced like a TopLevel."""

import numpy as np

from ._device import Device
from ._geometry import Triangles
from ._structures import Instance
from ._top_level import TopLevel


class Scene:
    """One mesh, one bottom level, one identity instance: Scene(dev, vertices, indices).

    vertices and indices as for vkas.Triangles; the build options as for Device.build_bottom_level. Traces like a
    TopLevel (intersect, occluded, intersect_all). Pickles through the serialized form, its bottom level with it.
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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
