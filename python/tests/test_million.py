"""A million rays in one call."""

import numpy as np

import oracle
import vkas


def test_one_million_rays(dev, rng):
    v, f = oracle.icosphere(4, jitter=0.03, rng=rng)  # 5120 triangles
    scene = vkas.Scene(dev, v, f)
    n = 1_000_000
    o = rng.uniform(-2, 2, (n, 3)).astype(np.float32)
    d = (rng.uniform(-0.8, 0.8, (n, 3)) - o).astype(np.float32)
    hits = scene.intersect(o, d)
    assert len(hits) == n and hits.t.dtype == np.float32 and hits.barycentrics.shape == (n, 2)
    assert 0.2 * n < hits.hit.sum() < n
    np.testing.assert_array_equal(scene.occluded(o, d), hits.hit)
    # a sample against the oracle
    k = rng.choice(n, 200, replace=False)
    tri = v[f].astype(np.float64)
    cls = oracle.triangles_vs_rays(tri, o[k].astype(np.float64), d[k].astype(np.float64), np.zeros(len(k)),
                                   np.full(len(k), np.inf))
    clean = cls.clean_rays()
    prim, t = cls.closest()
    np.testing.assert_array_equal(hits.primitive_id[k][clean], prim[clean])
    # the hit points lie on their triangles
    h = np.flatnonzero(hits.hit)[:100000]
    b = hits.barycentrics[h].astype(np.float64)
    tv = tri[hits.primitive_id[h]]
    p = tv[:, 0] * (1 - b[:, :1] - b[:, 1:]) + tv[:, 1] * b[:, :1] + tv[:, 2] * b[:, 1:]
    q = o[h].astype(np.float64) + d[h] * hits.t[h, None].astype(np.float64)
    assert np.abs(p - q).max() < 1e-4
