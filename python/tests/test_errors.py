"""Every error path: TypeError / ValueError naming the argument, vkas.ValidationError carrying the VUID."""

import numpy as np
import pytest

import oracle
import vkas
from vkas import RayFlags


@pytest.fixture(scope="module")
def scene(dev):
    v, f = oracle.icosphere(1)
    return vkas.Scene(dev, v, f, allow_update=False)


def rays(n=5):
    o = np.zeros((n, 3), np.float32)
    d = np.tile(np.float32([0, 0, 1]), (n, 1))
    return o, d


# -- rays ------------------------------------------------------------------------------------------------------

def test_ray_arrays(scene):
    o, d = rays()
    with pytest.raises(ValueError, match=r"^origins: expected an \(R, 3\) float32 array, got shape \(5, 2\)$"):
        scene.intersect(o[:, :2].copy(), d)
    with pytest.raises(TypeError, match=r"^origins: expected an \(R, 3\) float32 array \(float64 is converted\), "
                                        r"got dtype int64"):
        scene.intersect(np.zeros((5, 3), np.int64), d)
    with pytest.raises(TypeError, match="^directions: .*got dtype float16"):
        scene.intersect(o, d.astype(np.float16))
    with pytest.raises(TypeError, match="^origins: .*got dtype object"):
        scene.intersect(None, d)
    with pytest.raises(ValueError, match=r"^directions: expected an \(R, 3\) float32 array with R = 5 \(as "
                                         r"origins\), got shape \(4, 3\)"):
        scene.intersect(o, d[:4])
    with pytest.raises(ValueError, match="^origins: the float32 array is not C-contiguous"):
        scene.intersect(np.asfortranarray(o), d)
    with pytest.raises(ValueError, match="^directions: the float32 array is not C-contiguous"):
        scene.occluded(o, np.zeros((5, 6), np.float32)[:, ::2])
    with pytest.raises(ValueError, match="^origins: expected"):
        scene.intersect(np.zeros((2, 5, 3), np.float32), d)


@pytest.mark.parametrize("method", ["intersect", "occluded", "intersect_all"])
def test_ray_values(scene, method):
    call = getattr(scene, method)
    o, d = rays()
    bad = o.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"^origins: ray 3 has a non-finite origin \(0, nan, 0\).*06348"):
        call(bad, d)
    bad = d.copy()
    bad[2, 0] = np.inf
    with pytest.raises(ValueError, match=r"^directions: ray 2 has a non-finite direction.*06348"):
        call(o, bad)
    with pytest.raises(ValueError, match=r"^tmin: ray 0 has tmin nan.*06351"):
        call(o, d, tmin=np.nan)
    t = np.zeros(5, np.float32)
    t[4] = np.nan
    with pytest.raises(ValueError, match=r"^tmax: ray 4 .*06351"):
        call(o, d, tmax=t)
    with pytest.raises(ValueError, match=r"^tmin: ray 0 has tmin -1.*>= 0.*06349"):
        call(o, d, tmin=-1.0)
    with pytest.raises(ValueError, match=r"^tmin: ray 0 has tmin 2 > tmax 1 .*06350"):
        call(o, d, tmin=2.0, tmax=1.0)
    with pytest.raises(ValueError, match=r"^tmin: expected an \(R,\) \(R = 5\) float32 array, got shape \(4,\)"):
        call(o, d, tmin=np.zeros(4, np.float32))
    with pytest.raises(TypeError, match="^tmax: expected a number"):
        call(o, d, tmax="far")
    with pytest.raises(TypeError, match="^tmax: .*got dtype int32"):
        call(o, d, tmax=np.ones(5, np.int32))
    with pytest.raises(TypeError, match="^flags: expected an int, got float"):
        call(o, d, flags=1.0)
    with pytest.raises(ValueError, match="^flags: unknown ray flag bits 0x800"):
        call(o, d, flags=0x800)
    with pytest.raises(ValueError, match=r"^mask: must be in \[0, 255\], got 256"):
        call(o, d, mask=256)
    with pytest.raises(TypeError, match="^mask: expected an int, got bool"):
        call(o, d, mask=True)


@pytest.mark.parametrize("validation", [True, False])
@pytest.mark.parametrize("flags, vuid", [
    (RayFlags.CullBackFacingTrianglesKHR | RayFlags.CullFrontFacingTrianglesKHR, "06890"),
    (RayFlags.SkipTrianglesKHR | RayFlags.CullBackFacingTrianglesKHR, "06890"),
    (RayFlags.OpaqueKHR | RayFlags.NoOpaqueKHR, "06891"),
    (RayFlags.CullOpaqueKHR | RayFlags.NoOpaqueKHR, "06891"),
    (RayFlags.SkipTrianglesKHR | RayFlags.SkipAABBsKHR, "06889"),
])
def test_ray_flag_rules(dev, dev_novalidation, validation, flags, vuid):
    # With validation on vkas reports the rule (through the messenger); with it off the package checks it itself.
    device = dev if validation else dev_novalidation
    v, f = oracle.icosphere(0)
    scene = vkas.Scene(device, v, f)
    o, d = rays()
    for method in ("intersect", "occluded"):
        with pytest.raises(vkas.ValidationError) as e:
            getattr(scene, method)(o, d, flags=flags)
        assert e.value.vuid == f"VUID-RuntimeSpirv-OpRayQueryInitializeKHR-{vuid}"
        assert e.value.vuid in str(e.value) and e.value.message
        if validation:
            assert e.value.message.startswith(f"Validation Error: [ {e.value.vuid} ]")


def test_ray_flags_intersect_all(scene):
    o, d = rays()
    for flag in (RayFlags.OpaqueKHR, RayFlags.CullOpaqueKHR, RayFlags.CullNoOpaqueKHR,
                 RayFlags.TerminateOnFirstHitKHR):
        with pytest.raises(ValueError, match="^flags: intersect_all reports every hit"):
            scene.intersect_all(o, d, flags=flag)
    with pytest.raises(vkas.ValidationError, match="06890"):
        scene.intersect_all(o, d, flags=RayFlags.CullBackFacingTrianglesKHR | RayFlags.CullFrontFacingTrianglesKHR)
    scene.intersect_all(o, d, flags=RayFlags.NoOpaqueKHR)  # intersect_all's own flag: allowed
    with pytest.raises(ValueError, match=r"^max_hits: must be in \[1, "):
        scene.intersect_all(o, d, max_hits=0)
    r, h = scene.intersect_all(o, d, max_hits=1)
    assert np.all(np.bincount(r) <= 1)


# -- geometry --------------------------------------------------------------------------------------------------

def test_triangles():
    v = np.zeros((6, 3), np.float32)
    with pytest.raises(TypeError, match=r"^vertices: expected an \(N, 3\) float32 array .*got dtype int64"):
        vkas.Triangles(np.zeros((6, 3), np.int64))
    with pytest.raises(ValueError, match=r"^vertices: expected an \(N, 3\) float32 array, got shape \(6, 2\)"):
        vkas.Triangles(np.zeros((6, 2), np.float32))
    with pytest.raises(ValueError, match="^vertices: the float32 array is not C-contiguous"):
        vkas.Triangles(np.zeros((6, 6), np.float32)[:, 1::2])
    bad = v.copy()
    bad[4, 2] = np.inf
    with pytest.raises(ValueError, match=r"^vertices: must be finite .*vertices\[4\]"):
        vkas.Triangles(bad)
    bad = v.copy()
    bad[1, 1] = np.nan  # NaN outside x: not Vulkan's inactive marker
    with pytest.raises(ValueError, match=r"^vertices: must be finite"):
        vkas.Triangles(bad)
    bad = v.copy()
    bad[1, :] = np.nan  # a NaN x: an inactive triangle, allowed
    vkas.Triangles(bad)
    with pytest.raises(ValueError, match="^vertices: a triangle soup .*multiple of 3 vertices, got 5"):
        vkas.Triangles(v[:5])
    with pytest.raises(TypeError, match=r"^indices: expected an \(M, 3\) uint16/uint32/int32 array, got dtype float32"):
        vkas.Triangles(v, np.zeros((2, 3), np.float32))
    with pytest.raises(TypeError, match="^indices: .*got dtype bool"):
        vkas.Triangles(v, np.zeros((2, 3), bool))
    with pytest.raises(ValueError, match=r"^indices: .*got shape \(2, 4\)"):
        vkas.Triangles(v, np.zeros((2, 4), np.uint32))
    with pytest.raises(ValueError, match=r"^indices: face 1 is \[0, 6, 1\], out of range for 6 vertices"):
        vkas.Triangles(v, np.array([[0, 1, 2], [0, 6, 1]], np.uint32))
    with pytest.raises(ValueError, match=r"^indices: face 0 is \[-1, 1, 2\]"):
        vkas.Triangles(v, np.array([[-1, 1, 2]], np.int32))
    with pytest.raises(ValueError, match="^indices: the array is not C-contiguous"):
        vkas.Triangles(v, np.zeros((2, 6), np.uint32)[:, ::2])
    t = vkas.Triangles(v, np.array([[0, 1, 2]], np.int32))  # int32 converted (range checked)
    assert t.indices.dtype == np.uint32
    with pytest.raises(ValueError, match=r"^transform: expected a \(3, 4\) float32 array, got shape \(3, 3\)"):
        vkas.Triangles(v, transform=np.eye(3))
    with pytest.raises(ValueError, match=r"^transform: values must be finite"):
        vkas.Triangles(v, transform=np.full((3, 4), np.nan))
    with pytest.raises(ValueError, match="^transform: a \\(4, 4\\) transform must be affine"):
        vkas.Triangles(v, transform=np.ones((4, 4)))
    vkas.Triangles(v, transform=np.eye(4))
    with pytest.raises(TypeError, match="^opaque: expected a bool, got int"):
        vkas.Triangles(v, opaque=1)


def test_spheres():
    c = np.zeros((4, 3), np.float32)
    with pytest.raises(ValueError, match=r"^radii: expected an \(N,\) \(N = 4\) float32 array, got shape \(3,\)"):
        vkas.Spheres(c, np.ones(3, np.float32))
    with pytest.raises(ValueError, match=r"^radii: must be >= 0, radii\[2\] is -1"):
        vkas.Spheres(c, np.float32([1, 1, -1, 1]))
    with pytest.raises(ValueError, match=r"^radii: values must be finite"):
        vkas.Spheres(c, np.float32([1, 1, np.inf, 1]))
    bad = c.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match=r"^centers: values must be finite, centers\[0, 0\]"):
        vkas.Spheres(bad, 1.0)
    with pytest.raises(TypeError, match="^centers: "):
        vkas.Spheres(np.zeros((4, 3), np.int32), 1.0)


# -- builds ----------------------------------------------------------------------------------------------------

def test_build_arguments(dev):
    v, f = oracle.icosphere(0)
    tri = vkas.Triangles(v, f)
    sph = vkas.Spheres(v, 0.1)
    with pytest.raises(TypeError, match="^geometries: expected a list"):
        dev.build_bottom_level("triangles")
    with pytest.raises(TypeError, match=r"^geometries\[1\]: expected vkas.Triangles or vkas.Spheres, got int"):
        dev.build_bottom_level([tri, 3])
    with pytest.raises(vkas.ValidationError) as e:
        dev.build_bottom_level([tri, sph])
    assert e.value.vuid == "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03792"
    with pytest.raises(ValueError, match="^preference: expected one of 'default', 'fast_trace', 'fast_build', "
                                         "got 'fastest'"):
        dev.build_bottom_level([tri], preference="fastest")
    with pytest.raises(TypeError, match="^allow_update: expected a bool"):
        dev.build_bottom_level([tri], allow_update="yes")
    blas = dev.build_bottom_level([tri])
    with pytest.raises(TypeError, match="^blas: expected a vkas.BottomLevel, got Triangles"):
        vkas.Instance(tri)
    with pytest.raises(ValueError, match=r"^mask: must be in \[0, 255\], got 300"):
        vkas.Instance(blas, mask=300)
    with pytest.raises(ValueError, match=r"^custom_index: must be in \[0, 0xffffff\], got 16777216"):
        vkas.Instance(blas, custom_index=1 << 24)
    with pytest.raises(ValueError, match="^flags: unknown instance flag bits 0x40"):
        vkas.Instance(blas, flags=0x40)
    with pytest.raises(ValueError, match=r"^transform: expected a \(3, 4\) float32 array"):
        vkas.Instance(blas, transform=np.eye(3))
    with pytest.raises(TypeError, match=r"^instances\[0\]: expected a vkas.Instance"):
        dev.build_top_level(["blas"])
    other = vkas.Device()
    with pytest.raises(ValueError, match=r"^instances\[1\]: its bottom level belongs to another vkas.Device"):
        other.build_top_level([vkas.Instance(other.build_bottom_level([tri])), vkas.Instance(blas)])
    with pytest.raises(ValueError, match="^threads: must be in"):
        vkas.Device(threads=-1)
    with pytest.raises(TypeError, match="^validation: expected a bool"):
        vkas.Device(validation="on")
    with pytest.raises(TypeError, match="BottomLevel: use Device.build_bottom_level"):
        vkas.BottomLevel()
    with pytest.raises(TypeError, match="^device: expected a vkas.Device"):
        vkas.Scene(None, v, f)


def test_update_and_compact_rules(dev, dev_novalidation):
    v, f = oracle.icosphere(1)
    for device in (dev, dev_novalidation):
        fixed = device.build_bottom_level([vkas.Triangles(v, f)])
        with pytest.raises(vkas.ValidationError) as e:
            fixed.update([vkas.Triangles(v, f)])
        assert e.value.vuid == "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667"
        with pytest.raises(vkas.ValidationError) as e:
            fixed.compact()
        assert e.value.vuid == "VUID-VkCopyAccelerationStructureInfoKHR-src-03411"
        upd = device.build_bottom_level([vkas.Triangles(v, f)], allow_update=True)
        with pytest.raises(vkas.ValidationError) as e:
            upd.update([vkas.Triangles(v, f[:-1])])
        assert e.value.vuid == "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769"
        with pytest.raises(vkas.ValidationError) as e:
            upd.update([vkas.Triangles(v, f), vkas.Triangles(v, f)])
        assert e.value.vuid == "VUID-vkBuildAccelerationStructuresKHR-pInfos-03758"
        with pytest.raises(vkas.ValidationError) as e:
            upd.update([vkas.Spheres(v, 1.0)])
        assert e.value.vuid == "VUID-vkBuildAccelerationStructuresKHR-pInfos-03761"
        tlas = device.build_top_level([vkas.Instance(fixed)])
        with pytest.raises(vkas.ValidationError, match="03667"):
            tlas.update([vkas.Instance(fixed)])
        tlas = device.build_top_level([vkas.Instance(fixed)], allow_update=True)
        with pytest.raises(vkas.ValidationError, match="03769"):
            tlas.update([vkas.Instance(fixed), vkas.Instance(fixed)])
    # Rules only vkas sees (validation on): new index values in an update (03768), through the messenger.
    upd = dev.build_bottom_level([vkas.Triangles(v, f)], allow_update=True)
    with pytest.raises(vkas.ValidationError) as e:
        upd.update([vkas.Triangles(v, f[:, [1, 0, 2]].copy())])
    assert e.value.vuid == "VUID-vkBuildAccelerationStructuresKHR-pInfos-03768"
    assert e.value.message.startswith("Validation Error: [ VUID-vkBuildAccelerationStructuresKHR-pInfos-03768 ]")
    assert e.value.messages[0] == (e.value.vuid, e.value.message)
    upd.update([vkas.Triangles(v, f)])  # the structure is unharmed


def test_deserialize_errors(dev, dev_novalidation):
    v, f = oracle.icosphere(1)
    blas = dev.build_bottom_level([vkas.Triangles(v, f)])
    blob = blas.serialize()
    with pytest.raises(TypeError, match="^blob: expected bytes, got str"):
        dev.deserialize("blob")
    with pytest.raises(ValueError, match="^blob: .* too short"):
        dev.deserialize(b"VKAS")
    with pytest.raises(ValueError, match="^blob: truncated"):
        dev.deserialize(blob[:-10])
    damaged = bytearray(blob)
    damaged[len(blob) // 2] ^= 0x40
    with pytest.raises(vkas.ValidationError) as e:
        dev.deserialize(bytes(damaged))
    assert e.value.vuid == "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960"
    with pytest.raises(ValueError, match="^blob: not a valid serialized structure"):
        dev_novalidation.deserialize(bytes(damaged))
    wrong = bytearray(blob)
    wrong[0:16] = b"SOMETHING-ELSE!!"
    with pytest.raises(vkas.ValidationError, match="03414"):
        dev.deserialize(bytes(wrong))
    with pytest.raises(ValueError, match="^blob: serialized by an incompatible vkas"):
        dev_novalidation.deserialize(bytes(wrong))
    tlas = dev.build_top_level([vkas.Instance(blas), vkas.Instance(blas)])
    tblob = tlas.serialize()
    with pytest.raises(ValueError, match="^bottom_levels: the blob is a top level with 2 instances"):
        dev.deserialize(tblob)
    with pytest.raises(ValueError, match="^bottom_levels: the blob's top level has 2 instances, 1 bottom levels"):
        dev.deserialize(tblob, [blas])
    with pytest.raises(TypeError, match=r"^bottom_levels\[1\]: expected vkas.BottomLevel or None"):
        dev.deserialize(tblob, [blas, "blas"])
    with pytest.raises(ValueError, match=r"^bottom_levels\[0\]: belongs to another vkas.Device"):
        dev.deserialize(tblob, [dev_novalidation.deserialize(blob), blas])
    # bytearray, memoryview and uint8 arrays are blobs too
    for b in (bytearray(blob), memoryview(blob), np.frombuffer(blob, np.uint8)):
        assert dev.deserialize(b).serialize() == blob
