"""The acceleration structures' common part (_Structure: sizes, build flags, serialize, copy checks), BottomLevel,
Instance and the instance records of top levels."""

import numpy as np

from ._checks import _int, _transform
from ._errors import ValidationError
from ._flags import (_ALLOW_COMPACTION, _ALLOW_UPDATE, _GEOMETRY_KINDS, _IDENTITY, _INSTANCE_DTYPE, InstanceFlags,
                     _preference_of)
from ._geometry import _geometries


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

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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


_load_bottom.__module__ = "vkas"  # pickles name it vkas._load_bottom: the package re-exports it


class Instance:
    """An instance of a bottom level in a top level.

    transform: (3, 4) row-major object-to-world transform (float32, float64 converted; a (4, 4) affine one is
    accepted), None for the identity. mask: 8 bits, tested against the ray's mask. custom_index: 24 bits, reported
    as hits.custom_index. flags: vkas.InstanceFlags. sbt_offset: the 24-bit shader binding table record offset.
    """

    __module__ = "vkas"  # its public name (pickles, reprs): the package re-exports it

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
            # Inactive: reference 0. Its transform is still a VkTransformMatrixKHR, which must be invertible
            # (VUID-VkTransformMatrixKHR-matrix-03799), whether or not the instance is active: the identity.
            rec[k]["transform"] = _IDENTITY
            continue
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
