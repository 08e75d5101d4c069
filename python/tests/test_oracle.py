"""Every call against the double-precision brute-force oracle (oracle.py) on random meshes."""

import numpy as np
import pytest

import oracle
import vkas
from vkas import RayFlags


def _rays(rng, n, tmin=None, tmax=None):
    o, d = oracle.random_rays(rng, n)
    t0 = np.zeros(n, np.float32) if tmin is None else tmin
    t1 = np.full(n, np.inf, np.float32) if tmax is None else tmax
    return o, d, t0, t1


def _classify_triangles(tri, o, d, t0, t1):
    return oracle.triangles_vs_rays(tri.astype(np.float64), o.astype(np.float64), d.astype(np.float64),
                                    np.asarray(t0, np.float64), np.asarray(t1, np.float64))


def _check_closest(hits, cls, clean, prim_of=None):
    prim, t = cls.closest()
    rays = np.flatnonzero(clean)
    assert len(rays) > 0.8 * len(clean), "too few rays away from edges: the test is too weak"
    got = hits.primitive_id[rays] if prim_of is None else prim_of(hits)[rays]
    np.testing.assert_array_equal(got, prim[rays])
    hit = rays[prim[rays] >= 0]
    assert len(hit) > 0.1 * len(rays), "too few hits: the test is too weak"
    np.testing.assert_allclose(hits.t[hit], t[hit], rtol=2e-5, atol=1e-6)
    miss = rays[prim[rays] < 0]
    assert np.all(np.isinf(hits.t[miss]))
    for name in ("primitive_id", "geometry_index", "instance_id", "custom_index"):
        assert np.all(getattr(hits, name)[miss] == -1), name
    return hit, prim


@pytest.mark.parametrize("indexed", [False, True])
@pytest.mark.parametrize("preference", ["default", "fast_trace", "fast_build"])
def test_intersect_random_soup(dev, rng, indexed, preference):
    tri = oracle.random_soup(rng, 300)
    if indexed:
        vertices = tri.reshape(-1, 3)[::-1].copy()  # reversed: indices do the work
        indices = (len(vertices) - 1 - np.arange(len(vertices))).reshape(-1, 3).astype(np.uint32)
        mesh = vkas.Triangles(vertices, indices)
    else:
        mesh = vkas.Triangles(tri.reshape(-1, 3))
    blas = dev.build_bottom_level([mesh], preference=preference)
    tlas = dev.build_top_level([vkas.Instance(blas)])
    o, d, t0, t1 = _rays(rng, 1500)
    t0 = rng.uniform(0, 0.3, len(o)).astype(np.float32)
    t1 = np.where(rng.random(len(o)) < 0.5, np.inf, rng.uniform(0.5, 3, len(o))).astype(np.float32)
    hits = tlas.intersect(o, d, t0, t1)
    cls = _classify_triangles(tri, o, d, t0, t1)
    clean = cls.clean_rays()
    hit, prim = _check_closest(hits, cls, clean)
    r = np.arange(len(o))
    np.testing.assert_allclose(hits.barycentrics[hit, 0], cls.u[hit, prim[hit]], atol=1e-4)
    np.testing.assert_allclose(hits.barycentrics[hit, 1], cls.v[hit, prim[hit]], atol=1e-4)
    np.testing.assert_array_equal(hits.front_face[hit], cls.front[hit, prim[hit]])
    assert np.all(hits.geometry_index[hit] == 0) and np.all(hits.instance_id[hit] == 0)

    occ = tlas.occluded(o, d, t0, t1)
    np.testing.assert_array_equal(occ[clean], cls.hit[clean].any(axis=1))
    np.testing.assert_array_equal(occ, hits.hit)  # the closest hit exists exactly when some hit does

    ray_index, every = tlas.intersect_all(o, d, t0, t1)
    assert ray_index.dtype == np.int64 and np.all(np.diff(ray_index) >= 0)
    for i in r[clean][:400]:
        mine = every.primitive_id[ray_index == i]
        ts = every.t[ray_index == i]
        expected = np.flatnonzero(cls.hit[i])
        expected = expected[np.argsort(cls.t[i, expected])]
        np.testing.assert_array_equal(mine, expected)
        assert np.all(np.diff(ts) >= 0)
        np.testing.assert_allclose(ts, cls.t[i, expected], rtol=2e-5, atol=1e-6)
    # intersect_all's first hit is intersect's hit, on every ray (edges included: one traversal rule)
    first = np.full(len(o), -1)
    starts = np.flatnonzero(np.r_[True, np.diff(ray_index) != 0]) if len(ray_index) else np.array([], int)
    first[ray_index[starts]] = every.primitive_id[starts]
    np.testing.assert_array_equal(first, hits.primitive_id)


def test_instances_transforms_masks_custom_index(dev, rng):
    soups = [oracle.random_soup(rng, 120, 0.2), oracle.random_soup(rng, 80, 0.2)]
    # one bottom level of two geometries (one with a geometry transform), one of one
    g_xf = np.hstack([np.eye(3) * 0.7, rng.uniform(-0.2, 0.2, (3, 1))]).astype(np.float32)
    blas_a = dev.build_bottom_level([vkas.Triangles(soups[0].reshape(-1, 3)),
                                     vkas.Triangles(soups[1].reshape(-1, 3), transform=g_xf)])
    blas_b = dev.build_bottom_level([vkas.Triangles(soups[1].reshape(-1, 3))])
    transforms = []
    for _ in range(4):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        transforms.append(np.hstack([q * rng.uniform(0.5, 1.5), rng.uniform(-0.5, 0.5, (3, 1))]))
    masks = [0x01, 0x02, 0x04, 0xFF]
    insts = [vkas.Instance(blas_a if k % 2 == 0 else blas_b, transforms[k], mask=masks[k], custom_index=1000 + k)
             for k in range(4)]
    tlas = dev.build_top_level(insts)
    # the world-space primitive list: (instance, geometry, primitive)
    world, keys = [], []
    for k, inst in enumerate(insts):
        geoms = [(soups[0], None), (soups[1], g_xf)] if k % 2 == 0 else [(soups[1], None)]
        for gi, (soup, gx) in enumerate(geoms):
            p = soup.reshape(-1, 3).astype(np.float64)
            if gx is not None:
                p = oracle.apply(gx, p)
            world.append(oracle.apply(transforms[k], p).reshape(-1, 3, 3))
            keys += [(k, gi, j) for j in range(len(soup))]
    world = np.concatenate(world)
    keys = np.array(keys)
    o, d, t0, t1 = _rays(rng, 1500)
    for ray_mask in (0xFF, 0x05):
        hits = tlas.intersect(o, d, mask=ray_mask)
        cls = _classify_triangles(world, o, d, t0, t1)
        visible = np.array([(masks[k] & ray_mask) != 0 for k in keys[:, 0]])
        cls.hit &= visible[None]
        cls.ambiguous &= visible[None]
        clean = cls.clean_rays()
        prim, t = cls.closest()
        rays = np.flatnonzero(clean)
        hit = rays[prim[rays] >= 0]
        assert len(hit) > 100
        assert np.all(hits.primitive_id[rays[prim[rays] < 0]] == -1)
        np.testing.assert_array_equal(hits.instance_id[hit], keys[prim[hit], 0])
        np.testing.assert_array_equal(hits.geometry_index[hit], keys[prim[hit], 1])
        np.testing.assert_array_equal(hits.primitive_id[hit], keys[prim[hit], 2])
        np.testing.assert_array_equal(hits.custom_index[hit], 1000 + keys[prim[hit], 0])
        np.testing.assert_allclose(hits.t[hit], t[hit], rtol=1e-4, atol=1e-6)
        # facing is decided in object space: mirror-free rotations keep the world-space answer
        np.testing.assert_array_equal(hits.front_face[hit], cls.front[hit, prim[hit]])


def test_spheres(dev, rng):
    centers = rng.uniform(-1, 1, (200, 3)).astype(np.float32)
    radii = rng.uniform(0.02, 0.15, 200).astype(np.float32)
    blas = dev.build_bottom_level([vkas.Spheres(centers, radii)])
    assert blas.kind == "spheres"
    tlas = dev.build_top_level([vkas.Instance(blas, custom_index=7)])
    o, d, t0, t1 = _rays(rng, 2000)
    cls = oracle.spheres_vs_rays(centers.astype(np.float64), radii.astype(np.float64), o.astype(np.float64),
                                 d.astype(np.float64), t0.astype(np.float64), t1.astype(np.float64))
    hits = tlas.intersect(o, d)
    clean = cls.clean_rays()
    hit, prim = _check_closest(hits, cls, clean)
    assert np.all(hits.custom_index[hit] == 7)
    assert np.all(hits.barycentrics[hit] == 0) and not hits.front_face.any()
    np.testing.assert_array_equal(tlas.occluded(o, d)[clean], cls.hit[clean].any(axis=1))
    ray_index, every = tlas.intersect_all(o, d)
    for i in np.flatnonzero(clean)[:300]:
        expected = np.flatnonzero(cls.hit[i])
        expected = expected[np.argsort(cls.t[i, expected])]
        np.testing.assert_array_equal(every.primitive_id[ray_index == i], expected)


def test_ray_flags_against_oracle(dev, rng):
    tri = oracle.random_soup(rng, 200)
    opaque = dev.build_bottom_level([vkas.Triangles(tri.reshape(-1, 3), opaque=True)])
    clear = dev.build_bottom_level([vkas.Triangles(tri.reshape(-1, 3), opaque=False)])
    o, d, t0, t1 = _rays(rng, 1000)
    cls = _classify_triangles(tri, o, d, t0, t1)
    for blas in (opaque, clear):
        tlas = dev.build_top_level([vkas.Instance(blas)])
        for flag, keep in ((RayFlags.CullBackFacingTrianglesKHR, cls.front),
                           (RayFlags.CullFrontFacingTrianglesKHR, ~cls.front)):
            sub = oracle.Classified(cls.hit & keep, cls.ambiguous & keep, cls.t, cls.u, cls.v, cls.front)
            sub.t = np.where(sub.hit, cls.t, np.inf)
            clean = sub.clean_rays()
            _check_closest(tlas.intersect(o, d, flags=flag), sub, clean)
            np.testing.assert_array_equal(tlas.occluded(o, d, flags=flag)[clean], sub.hit[clean].any(axis=1))
            ray_index, every = tlas.intersect_all(o, d, flags=flag)
            assert np.all(every.front_face == (flag == RayFlags.CullBackFacingTrianglesKHR))
        assert not tlas.intersect(o, d, flags=RayFlags.SkipTrianglesKHR).hit.any()
        assert not tlas.occluded(o, d, flags=RayFlags.SkipTrianglesKHR).any()
        culled = RayFlags.CullOpaqueKHR if blas is opaque else RayFlags.CullNoOpaqueKHR
        kept = RayFlags.CullNoOpaqueKHR if blas is opaque else RayFlags.CullOpaqueKHR
        assert not tlas.intersect(o, d, flags=culled).hit.any()
        assert tlas.intersect(o, d, flags=kept) == tlas.intersect(o, d)
        # OpaqueKHR / NoOpaqueKHR override the geometry: both still report the closest hit (no any-hit shader)
        assert tlas.intersect(o, d, flags=RayFlags.NoOpaqueKHR) == tlas.intersect(o, d)
        assert tlas.intersect(o, d, flags=RayFlags.OpaqueKHR) == tlas.intersect(o, d)
        # TerminateOnFirstHitKHR: some hit, where there is one
        first = tlas.intersect(o, d, flags=RayFlags.TerminateOnFirstHitKHR)
        np.testing.assert_array_equal(first.hit, tlas.intersect(o, d).hit)
    # instance flags: FORCE_NO_OPAQUE makes the opaque geometry cullable by CullNoOpaqueKHR
    tlas = dev.build_top_level([vkas.Instance(opaque, flags=vkas.InstanceFlags.FORCE_NO_OPAQUE)])
    assert not tlas.intersect(o, d, flags=RayFlags.CullNoOpaqueKHR).hit.any()
    # TRIANGLE_FLIP_FACING inverts front_face
    base = dev.build_top_level([vkas.Instance(opaque)]).intersect(o, d)
    flipped = dev.build_top_level([vkas.Instance(opaque, flags=vkas.InstanceFlags.TRIANGLE_FLIP_FACING)]
                                  ).intersect(o, d)
    np.testing.assert_array_equal(flipped.front_face[base.hit], ~base.front_face[base.hit])


def test_directions_are_not_normalised(dev, rng):
    v, f = oracle.icosphere(1)
    scene = vkas.Scene(dev, v, f)
    o = np.zeros((100, 3), np.float32)
    d = rng.normal(size=(100, 3)).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    h1 = scene.intersect(o, d)
    h2 = scene.intersect(o, 2 * d)
    np.testing.assert_allclose(h2.t * 2, h1.t, rtol=1e-6)
    np.testing.assert_array_equal(h1.primitive_id, h2.primitive_id)
    # tmax in units of the direction's length
    assert not scene.occluded(o, 4 * d, tmax=0.2).any()
    assert scene.occluded(o, 4 * d, tmax=0.3).all()


def test_empty_inputs(dev):
    scene = vkas.Scene(dev, np.zeros((0, 3), np.float32))
    o = np.zeros((3, 3), np.float32)
    d = np.tile(np.float32([0, 0, 1]), (3, 1))
    assert not scene.intersect(o, d).hit.any()
    empty = np.zeros((0, 3), np.float32)
    h = scene.intersect(empty, empty)
    assert len(h) == 0 and h.barycentrics.shape == (0, 2)
    r, a = scene.intersect_all(empty, empty)
    assert len(r) == 0 and len(a) == 0
    assert scene.occluded(empty, empty).shape == (0,)
    tlas = dev.build_top_level([])
    assert not tlas.intersect(o, d).hit.any()


def test_float64_inputs_are_converted_once(dev, rng):
    tri = oracle.random_soup(rng, 50)
    s32 = vkas.Scene(dev, tri.reshape(-1, 3))
    s64 = vkas.Scene(dev, tri.reshape(-1, 3).astype(np.float64))
    o, d = oracle.random_rays(rng, 500)
    assert s32.intersect(o, d) == s64.intersect(o.astype(np.float64), d.astype(np.float64))
    # float64 arrays need not be contiguous (they are copied anyway); lists are arrays too
    o64 = np.asfortranarray(o.astype(np.float64))
    assert s32.intersect(o64, d) == s32.intersect(o, d)
    assert s32.intersect(o.tolist(), d.tolist()) == s32.intersect(o, d)


def test_inactive_instances_keep_their_ids(dev, dev_novalidation):
    # None is an inactive instance (reference 0): it keeps its id and is never hit. Its record still holds a
    # VkTransformMatrixKHR, which must be invertible (VUID-VkTransformMatrixKHR-matrix-03799) even where the instance
    # is inactive, so a device with validation on accepts the list as one without it does.
    tri = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], np.float32)
    for device in (dev, dev_novalidation):
        blas = device.build_bottom_level([vkas.Triangles(tri)])
        at = [np.hstack([np.eye(3), [[3.0 * k], [0], [0]]]) for k in range(3)]
        tlas = device.build_top_level([vkas.Instance(blas, at[0]), None, vkas.Instance(blas, at[2])])
        o = np.array([[3.0 * k, 0, 1] for k in range(3)], np.float32)
        d = np.tile(np.array([[0, 0, -1]], np.float32), (3, 1))
        hits = tlas.intersect(o, d)
        np.testing.assert_array_equal(hits.instance_id, [0, -1, 2])
        np.testing.assert_allclose(hits.t, [1, np.inf, 1])
        assert tlas.instances[1] is None
