"""Results (and structures) are the same for any thread count."""

import threading

import numpy as np

import oracle
import vkas


def _mesh(rng):
    v, f = oracle.icosphere(5, jitter=0.02, rng=rng)  # 20480 triangles: builds take the multi-threaded path
    return v, f


def test_thread_count_does_not_change_anything(rng):
    v, f = _mesh(rng)
    o, d = oracle.random_rays(rng, 100000)
    d[:5000] = d[0]  # a coherent bundle too (packets)
    o[:5000] = o[0]
    results = []
    for threads in (1, 0, 3):
        dev = vkas.Device(threads=threads)
        blas = dev.build_bottom_level([vkas.Triangles(v, f)], preference="fast_trace")
        tlas = dev.build_top_level([vkas.Instance(blas), vkas.Instance(blas, np.float32(
            [[0.5, 0, 0, 1.5], [0, 0.5, 0, 0], [0, 0, 0.5, 0]]), custom_index=3)])
        hits = tlas.intersect(o, d)
        occ = tlas.occluded(o, d)
        ray_index, every = tlas.intersect_all(o[:20000], d[:20000])
        results.append((blas.serialize(), hits, occ, ray_index, every))
    base = results[0]
    assert base[1].hit.sum() > 10000
    for other in results[1:]:
        assert other[0] == base[0]  # the same bytes
        assert other[1] == base[1]
        np.testing.assert_array_equal(other[2], base[2])
        np.testing.assert_array_equal(other[3], base[3])
        assert other[4] == base[4]


def test_concurrent_python_threads(dev, rng):
    # Calls release the GIL: several Python threads may trace one structure at once.
    v, f = oracle.icosphere(3)
    scene = vkas.Scene(dev, v, f)
    o, d = oracle.random_rays(rng, 50000)
    expected = scene.intersect(o, d)
    out = [None] * 4
    def work(k):
        out[k] = scene.intersect(o, d)
    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(h == expected for h in out)
