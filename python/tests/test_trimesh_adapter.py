"""vkas.trimesh.RayMeshIntersector against trimesh's documented semantics (trimesh itself is not needed)."""

from types import SimpleNamespace

import numpy as np
import pytest

import oracle
import vkas
import vkas.trimesh


@pytest.fixture(scope="module")
def sphere():
    v, f = oracle.icosphere(2)
    # as trimesh has them: float64 vertices, int64 faces
    return SimpleNamespace(vertices=v.astype(np.float64), faces=f.astype(np.int64))


def test_documented_example(sphere):
    # trimesh's ray example: two rays along +z at an icosphere, one through it, one past it
    intersector = vkas.trimesh.RayMeshIntersector(sphere)
    ray_origins = np.array([[0, 0, -3], [2, 2, -3]])
    ray_directions = np.array([[0, 0, 1], [0, 0, 1]])
    locations, index_ray, index_tri = intersector.intersects_location(ray_origins, ray_directions)
    assert locations.shape == (2, 3) and locations.dtype == np.float64
    np.testing.assert_array_equal(index_ray, [0, 0])
    assert index_ray.dtype == np.int64 and index_tri.dtype == np.int64
    np.testing.assert_allclose(np.abs(locations[:, 2]), 1.0, atol=0.05)
    assert locations[0, 2] < 0 < locations[1, 2]  # closest first
    first = intersector.intersects_first(ray_origins, ray_directions)
    assert first.dtype == np.int64 and first.shape == (2,) and first[1] == -1 and first[0] == index_tri[0]
    anyhit = intersector.intersects_any(ray_origins, ray_directions)
    assert anyhit.dtype == bool and anyhit.tolist() == [True, False]


def test_intersects_id(sphere, rng):
    intersector = vkas.trimesh.RayMeshIntersector(sphere)
    o, d = oracle.random_rays(rng, 2000, spread=3)
    index_tri, index_ray = intersector.intersects_id(o, d)
    assert index_tri.shape == index_ray.shape and index_tri.dtype == np.int64
    scene = vkas.Scene(vkas.Device(), sphere.vertices, sphere.faces)
    r, h = scene.intersect_all(o, d)
    np.testing.assert_array_equal(index_ray, r)
    np.testing.assert_array_equal(index_tri, h.primitive_id)
    # multiple_hits=False: the first hit of each ray that hits
    t1, r1 = intersector.intersects_id(o, d, multiple_hits=False)
    first = intersector.intersects_first(o, d)
    np.testing.assert_array_equal(r1, np.flatnonzero(first >= 0))
    np.testing.assert_array_equal(t1, first[first >= 0])
    # max_hits, return_locations
    t2, r2, loc = intersector.intersects_id(o, d, max_hits=1, return_locations=True)
    np.testing.assert_array_equal(t2, t1)
    np.testing.assert_array_equal(r2, r1)
    tri = sphere.vertices[sphere.faces[t2]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.abs(np.einsum("ij,ij->i", loc - tri[:, 0], n)).max() < 1e-5  # on the triangles' planes
    # intersects_any is "some hit"
    np.testing.assert_array_equal(intersector.intersects_any(o, d), first >= 0)
    # directions need not be unit vectors (trimesh normalises them; the hits are the same)
    np.testing.assert_array_equal(intersector.intersects_first(o, d * 7.5), first)


def test_contains_points(sphere, rng):
    intersector = vkas.trimesh.RayMeshIntersector(sphere)
    p = rng.uniform(-1.5, 1.5, (3000, 3))
    r = np.linalg.norm(p, axis=1)
    keep = np.abs(r - 1) > 0.05  # away from the (faceted) surface
    inside = intersector.contains_points(p[keep])
    np.testing.assert_array_equal(inside, r[keep] < 1)


def test_adapter_errors(sphere):
    intersector = vkas.trimesh.RayMeshIntersector(sphere)
    with pytest.raises(ValueError, match="^ray_directions"):
        intersector.intersects_first(np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="^ray_origins"):
        intersector.intersects_any(np.zeros((3, 2)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="^indices: face"):
        vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=np.zeros((3, 3)), faces=np.array([[0, 1, 5]])))
