"""update, compact, clone, serialize/deserialize round trips, and pickling."""

import pickle

import numpy as np
import pytest

import oracle
import vkas


def _scene_parts(dev, rng, **kw):
    v, f = oracle.icosphere(2, jitter=0.05, rng=rng)
    blas = dev.build_bottom_level([vkas.Triangles(v, f)], **kw)
    return v, f, blas


def test_update_matches_a_fresh_build(dev, rng):
    v, f, blas = _scene_parts(dev, rng, allow_update=True)
    tlas = dev.build_top_level([vkas.Instance(blas)])
    o, d = oracle.random_rays(rng, 3000, spread=3)
    before = tlas.intersect(o, d)
    moved = (v * 1.3 + np.float32([0.2, 0, 0])).astype(np.float32)
    blas.update([vkas.Triangles(moved, f)])
    after = tlas.intersect(o, d)  # the top level refits itself: the bottom level changed
    fresh = vkas.Scene(dev, moved, f).intersect(o, d)
    np.testing.assert_array_equal(after.primitive_id, fresh.primitive_id)
    np.testing.assert_allclose(after.t[after.hit], fresh.t[fresh.hit], rtol=1e-6)
    assert not np.array_equal(after.t, before.t)
    # back to the original positions: the original hits, exactly
    blas.update([vkas.Triangles(v, f)])
    assert tlas.intersect(o, d) == before


def test_top_level_update(dev, rng):
    v, f, blas = _scene_parts(dev, rng)
    tlas = dev.build_top_level([vkas.Instance(blas)], allow_update=True)
    o, d = oracle.random_rays(rng, 2000, spread=3)
    shift = np.float32([[1, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, 0]])
    tlas.update([vkas.Instance(blas, shift, custom_index=9)])
    fresh = dev.build_top_level([vkas.Instance(blas, shift, custom_index=9)])
    a, b = tlas.intersect(o, d), fresh.intersect(o, d)
    np.testing.assert_array_equal(a.primitive_id, b.primitive_id)
    np.testing.assert_array_equal(a.custom_index, b.custom_index)
    assert (a.custom_index[a.hit] == 9).all()


def test_compact_and_clone(dev, rng):
    v, f, blas = _scene_parts(dev, rng, allow_compaction=True)
    small = blas.compact()
    assert small.size == blas.size and small.allocated_size <= blas.allocated_size
    assert small.allow_compaction and small.kind == "triangles" and small.primitive_count == len(f)
    o, d = oracle.random_rays(rng, 2000, spread=3)
    ref = dev.build_top_level([vkas.Instance(blas)]).intersect(o, d)
    assert dev.build_top_level([vkas.Instance(small)]).intersect(o, d) == ref
    assert dev.build_top_level([vkas.Instance(blas.clone())]).intersect(o, d) == ref
    tlas = dev.build_top_level([vkas.Instance(small)], allow_compaction=True)
    assert tlas.compact().intersect(o, d) == ref
    # a compacted allow_update structure still updates
    _, _, upd = _scene_parts(dev, rng, allow_update=True, allow_compaction=True)
    upd.compact().update([vkas.Triangles(v * 2, f)])


def test_serialize_round_trip(dev, rng):
    v, f, blas = _scene_parts(dev, rng, preference="fast_trace", allow_update=True)
    spheres = dev.build_bottom_level([vkas.Spheres(rng.uniform(-1, 1, (50, 3)), 0.1)])
    insts = [vkas.Instance(blas), vkas.Instance(spheres, custom_index=5, mask=0x0F),
             vkas.Instance(blas, np.float32([[0.5, 0, 0, 2], [0, 0.5, 0, 0], [0, 0, 0.5, 0]]), flags=2)]
    tlas = dev.build_top_level(insts)
    o, d = oracle.random_rays(rng, 3000, spread=3)
    ref = tlas.intersect(o, d)
    blob = blas.serialize()
    assert isinstance(blob, bytes) and blob[:16] == b"VKAS-SERIALIZED2"
    loaded = dev.deserialize(blob)
    assert isinstance(loaded, vkas.BottomLevel) and loaded.serialize() == blob
    assert loaded.allow_update and loaded.preference == "fast_trace"
    loaded.update([vkas.Triangles(v, f)])  # what a deserialized structure remembers is enough to update it
    # a top level: its bottom levels again, in instance order
    copies = {id(b): dev.deserialize(b.serialize()) for b in (blas, spheres)}
    top = dev.deserialize(tlas.serialize(), [copies[id(b)] for b in tlas.bottom_levels])
    assert isinstance(top, vkas.TopLevel)
    assert top.intersect(o, d) == ref
    # its instances are read back from the records
    for a, b in zip(top.instances, insts):
        assert (a.mask, a.custom_index, int(a.flags)) == (b.mask, b.custom_index, int(b.flags))
        np.testing.assert_array_equal(a.transform, b.transform)
    # into another device
    other = vkas.Device(validation=False, threads=1)
    top2 = other.deserialize(tlas.serialize(), [other.deserialize(b.serialize()) for b in tlas.bottom_levels])
    assert top2.intersect(o, d) == ref


def test_pickle(dev, rng):
    v, f = oracle.icosphere(2)
    scene = vkas.Scene(dev, v, f)
    o, d = oracle.random_rays(rng, 2000, spread=3)
    ref = scene.intersect(o, d)
    s2 = pickle.loads(pickle.dumps(scene))
    assert isinstance(s2, vkas.Scene) and s2.intersect(o, d) == ref
    assert s2.device is not dev and s2.device.validation == dev.validation
    # a top level sharing one bottom level between instances: one copy of it comes back
    blas = scene.bottom_level
    tlas = dev.build_top_level([vkas.Instance(blas), vkas.Instance(blas, np.float32(
        [[1, 0, 0, 3], [0, 1, 0, 0], [0, 0, 1, 0]]), custom_index=4)])
    t2 = pickle.loads(pickle.dumps(tlas))
    assert t2.bottom_levels[0] is t2.bottom_levels[1]
    assert t2.intersect(o, d) == tlas.intersect(o, d)
    b2 = pickle.loads(pickle.dumps(blas))
    assert b2.serialize() == blas.serialize()
    d2 = pickle.loads(pickle.dumps(vkas.Device(validation=False, threads=2)))
    assert (d2.validation, d2.threads) == (False, 2)
    e = pickle.loads(pickle.dumps(vkas.ValidationError("VUID-x", "message")))
    assert (e.vuid, e.message) == ("VUID-x", "message")
    # a pickled Hits is plain numpy arrays
    assert pickle.loads(pickle.dumps(ref)) == ref
