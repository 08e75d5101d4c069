"""TopLevel: the structure rays are traced through (instances, refits, copies; intersect, occluded and
intersect_all), and Hits, what tracing returns."""

import threading

import numpy as np

from ._checks import _float32, _int, _rows3, _shape_text, _t
from ._errors import ValidationError
from ._flags import RayFlags, _flag_rules, _ray_flags
from ._structures import _instances, _records, _Structure


class TopLevel(_Structure):
    """A top-level acceleration structure: what rays are traced through."""

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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


_load_top.__module__ = "vkas"  # pickles name it vkas._load_top: the package re-exports it


class Hits:
    """Hits of a batch of rays, one entry per ray (intersect) or per hit (intersect_all).

    t (float32, inf on a miss), primitive_id, geometry_index, instance_id, custom_index (int32, -1 on a miss),
    barycentrics (n, 2) float32 (0 on a miss and for spheres), front_face (bool; False on a miss and for spheres).
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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
