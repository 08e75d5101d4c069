"""Rays through shared edges and vertices hit exactly once."""

import numpy as np

import oracle
import vkas


def test_grid_edges_and_vertices_hit_exactly_once(dev):
    n = 16
    v, f = oracle.grid(n)  # coordinates multiples of 1/8: every edge point below is exact
    scene = vkas.Scene(dev, v, f)
    s = 1.0 / 8
    # every interior vertex, every edge midpoint (horizontal, vertical, diagonal), straight down and slanted
    k = np.arange(1, 2 * n) * s / 2
    xy = np.stack(np.meshgrid(k, k), -1).reshape(-1, 2)
    points = np.column_stack([xy, np.zeros(len(xy))])
    for direction in ([0, 0, -1], [0.25, -0.125, -1], [-1, 0.5, -0.75], [1, 1, -1]):
        d = np.tile(np.float32(direction), (len(points), 1))
        o = (points - 2 * d).astype(np.float32)  # exact: powers of two
        ray_index, hits = scene.intersect_all(o, d)
        counts = np.bincount(ray_index, minlength=len(o))
        assert np.all(counts == 1), (direction, np.flatnonzero(counts != 1)[:10], counts[counts != 1][:10])
        assert scene.intersect(o, d).hit.all()
        assert scene.occluded(o, d).all()


def test_closed_mesh_from_inside_hits_exactly_once(dev, rng):
    v, f = oracle.icosphere(3, jitter=0.05, rng=rng)  # 1280 triangles, not planar anywhere
    scene = vkas.Scene(dev, v, f)
    center = np.zeros(3, np.float32)
    # random directions, and directions aimed exactly at every vertex and every edge midpoint
    d = rng.normal(size=(20000, 3))
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    mids = (v[edges[:, 0]].astype(np.float64) + v[edges[:, 1]]) / 2
    d = np.concatenate([d, v, mids]).astype(np.float32)
    o = np.tile(center, (len(d), 1))
    ray_index, hits = scene.intersect_all(o, d)
    counts = np.bincount(ray_index, minlength=len(o))
    assert np.all(counts == 1), np.flatnonzero(counts != 1)[:10]
    np.testing.assert_array_equal(hits.primitive_id, scene.intersect(o, d).primitive_id)
    assert not hits.front_face.any()  # seen from inside: back faces
    # from outside through the middle: in and out, exactly two
    o2 = (-3 * d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    d2 = (-o2).astype(np.float32)
    ray_index, hits = scene.intersect_all(o2, d2)
    counts = np.bincount(ray_index, minlength=len(o2))
    assert np.all(counts == 2), np.flatnonzero(counts != 2)[:10]
    assert np.all(hits.front_face[0::2]) and not np.any(hits.front_face[1::2])


def test_shared_edges_of_instances_meet_exactly(dev):
    # two instances of one square, side by side, sharing an edge through their transforms
    v = np.float32([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    f = np.uint32([[0, 1, 2], [0, 2, 3]])
    blas = dev.build_bottom_level([vkas.Triangles(v, f)])
    right = np.float32([[1, 0, 0, 1], [0, 1, 0, 0], [0, 0, 1, 0]])
    tlas = dev.build_top_level([vkas.Instance(blas), vkas.Instance(blas, right)])
    y = np.arange(1, 64) / 64
    o = np.column_stack([np.ones_like(y), y, np.ones_like(y)]).astype(np.float32)
    d = np.tile(np.float32([0, 0, -1]), (len(o), 1))
    ray_index, hits = tlas.intersect_all(o, d)
    assert np.all(np.bincount(ray_index, minlength=len(o)) == 1)
