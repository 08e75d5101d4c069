"""Every array the package accepts, fed every kind of bad array (issue 35): NaN, inf, out-of-range indices, wrong
dtypes, wrong shapes, non-contiguous, misaligned and zero-size arrays. Each must raise TypeError, ValueError or
vkas.ValidationError naming the argument, never crash the interpreter and never read memory it was not given; the
arrays that may legitimately be empty (no rays, no triangles) must give an empty, well-formed answer instead.

test_errors.py pins the exact messages of the common cases; this file is the sweep over every entry point.
"""

import numpy as np
import pytest

import oracle
import vkas

ERRORS = (TypeError, ValueError, vkas.ValidationError)


def misaligned(a):
    """A C-contiguous copy of `a` whose data starts one byte past an aligned address."""
    a = np.ascontiguousarray(a)
    raw = np.zeros(a.nbytes + 1, np.uint8)
    out = raw[1:].view(a.dtype).reshape(a.shape)
    out[...] = a
    assert not out.flags.aligned and out.flags.c_contiguous
    return out


def bad_float_arrays(good):
    """(label, array) pairs, each wrong for an argument whose good value is the float32 array `good`."""
    rows = good.shape[0]
    cases = []
    for value in (np.nan, np.inf, -np.inf):
        a = good.copy()
        a.flat[a.size // 2] = value
        cases.append((f"{value} inside", a))
    cases += [
        ("int64", good.astype(np.int64)),
        ("float16", good.astype(np.float16)),
        ("complex", good.astype(np.complex64)),
        ("bool", good.astype(bool)),
        ("object", good.astype(object)),
        ("strings", good.astype(str)),
        ("big-endian float32", good.astype(">f4")),
        ("Fortran order", np.asfortranarray(good) if good.ndim > 1 else good[::-1][::-1]),
        ("every other row", np.repeat(good, 2, axis=0)[::2]),
        ("misaligned", misaligned(good)),
        ("None", None),
        ("a string", "0, 0, 0"),
        ("nested ragged lists", [[0, 0], [0]]),
    ]
    if good.ndim == 2:
        cases += [
            ("flat", good.ravel()),
            ("one column short", good[:, :-1].copy()),
            ("an extra axis", good[None]),
        ]
    if rows > 1:
        cases.append(("a row short", good[:-1].copy()))
    return [c for c in cases if not (c[0] == "Fortran order" and c[1].flags.c_contiguous)]


def expect_clean_error(call, name):
    with pytest.raises(ERRORS) as info:
        call()
    assert name in str(info.value), f"the message should name {name!r}: {info.value}"


def expect_no_crash(call):
    """An argument vkas may accept or refuse (a NaN x marks an inactive vertex, a float64 NaN becomes float32 NaN,
    ...): either way a clean answer, and a refusal is an exception of ours."""
    try:
        call()
    except ERRORS:
        pass


V, F = oracle.icosphere(1)
V = V.astype(np.float32)
F = F.astype(np.uint32)


@pytest.fixture(scope="module")
def scene(dev):
    return vkas.Scene(dev, V, F, allow_update=False)


@pytest.fixture(scope="module")
def scene_novalidation(dev_novalidation):
    return vkas.Scene(dev_novalidation, V, F, allow_update=False)


def some_rays(n=8):
    o = np.zeros((n, 3), np.float32)
    o[:, 2] = -3
    d = np.tile(np.float32([0, 0, 1]), (n, 1))
    return o, d


# -- vertices, indices, transforms of a triangle geometry ---------------------------------------------------

@pytest.mark.parametrize("label,bad", bad_float_arrays(V), ids=lambda x: x if isinstance(x, str) else "")
def test_vertices(dev, label, bad):
    if label == "nan inside":
        # A NaN coordinate other than x is an error; a NaN x marks the vertex inactive (Vulkan's rule).
        expect_no_crash(lambda: dev.build_bottom_level([vkas.Triangles(bad, F)]))
        return
    expect_clean_error(lambda: vkas.Triangles(bad, F), "vertices")
    expect_clean_error(lambda: vkas.Scene(dev, bad, F), "vertices")


def test_vertices_nan_y_is_an_error(dev):
    v = V.copy()
    v[5, 1] = np.nan
    expect_clean_error(lambda: vkas.Triangles(v, F), "vertices")


INDEX_CASES = [
    ("one past the last vertex", lambda: np.where(F == F.max(), len(V), F).astype(np.uint32)),
    ("2**32 - 1", lambda: np.where(F == 0, 2**32 - 1, F).astype(np.uint32)),
    ("negative int32", lambda: np.where(F == 0, -1, F).astype(np.int32)),
    ("huge int64", lambda: np.where(F == 0, 2**40, F).astype(np.int64)),
    ("uint16 past the end", lambda: np.where(F == 0, 65535, F).astype(np.uint16)),
    ("float indices", lambda: F.astype(np.float32)),
    ("bool indices", lambda: F.astype(bool)),
    ("object indices", lambda: F.astype(object)),
    ("flat indices", lambda: F.ravel()),
    ("four a face", lambda: np.zeros((len(F), 4), np.uint32)),
    ("Fortran order uint32", lambda: np.asfortranarray(F)),
    ("every other face uint32", lambda: np.repeat(F, 2, axis=0)[::2]),
    ("misaligned uint32", lambda: misaligned(F)),
    ("misaligned uint16", lambda: misaligned(F.astype(np.uint16))),
    ("a string", lambda: "0 1 2"),
]


@pytest.mark.parametrize("label,make", INDEX_CASES, ids=[c[0] for c in INDEX_CASES])
def test_indices(dev, label, make):
    bad = make()
    expect_clean_error(lambda: vkas.Triangles(V, bad), "indices")
    expect_clean_error(lambda: vkas.Scene(dev, V, bad), "indices")


def test_triangle_soup_of_the_wrong_length():
    expect_clean_error(lambda: vkas.Triangles(V[:7]), "vertices")


@pytest.mark.parametrize("label,bad", [c for c in bad_float_arrays(np.eye(3, 4, dtype=np.float32)) if c[0] != "None"],
                         ids=lambda x: x if isinstance(x, str) else "")  # None: the identity
def test_geometry_and_instance_transforms(dev, label, bad):
    expect_clean_error(lambda: vkas.Triangles(V, F, transform=bad), "transform")
    blas = dev.build_bottom_level([vkas.Triangles(V, F)])
    expect_clean_error(lambda: vkas.Instance(blas, transform=bad), "transform")


def test_a_non_affine_4x4_transform(dev):
    t = np.eye(4, dtype=np.float32)
    t[3, 0] = 1
    expect_clean_error(lambda: vkas.Triangles(V, F, transform=t), "transform")


# -- spheres ------------------------------------------------------------------------------------------------

C = np.float32([[0, 0, 0], [2, 0, 0], [0, 3, 1]])
R = np.float32([0.5, 1, 0.25])


@pytest.mark.parametrize("label,bad", bad_float_arrays(C), ids=lambda x: x if isinstance(x, str) else "")
def test_sphere_centers(label, bad):
    # One center short is a count the radii do not match: the message names radii.
    expect_clean_error(lambda: vkas.Spheres(bad, R), "radii" if label == "a row short" else "centers")


@pytest.mark.parametrize("label,bad", bad_float_arrays(R) + [("negative", -R)],
                         ids=lambda x: x if isinstance(x, str) else "")
def test_sphere_radii(label, bad):
    expect_clean_error(lambda: vkas.Spheres(C, bad), "radii")


# -- rays ----------------------------------------------------------------------------------------------------

O, D = some_rays()
RAY_CASES = ([("origins", label, bad) for label, bad in bad_float_arrays(O)]
             + [("directions", label, bad) for label, bad in bad_float_arrays(D)]
             + [("tmin", label, bad) for label, bad in bad_float_arrays(np.zeros(len(O), np.float32))]
             + [("tmax", label, bad) for label, bad in bad_float_arrays(np.full(len(O), 10, np.float32))
                if label not in ("inf inside",)])


@pytest.mark.parametrize("method", ["intersect", "occluded", "intersect_all"])
@pytest.mark.parametrize("arg,label,bad", RAY_CASES, ids=[f"{c[0]}-{c[1]}" for c in RAY_CASES])
def test_rays(scene, scene_novalidation, method, arg, label, bad):
    kwargs = {"origins": O, "directions": D, "tmin": 0.0, "tmax": np.inf, arg: bad}
    # -inf tmin and a nan tmax break OpRayQueryInitializeKHR's value rules; the device without validation checks the
    # arguments' form only, and the values it may trace as it likes: never a crash.
    if (arg, label) == ("tmin", "inf inside"):
        i = len(O) // 2  # this ray's interval [inf, inf] is valid and empty: a miss
        result = getattr(scene, method)(**kwargs)
        if method == "intersect":
            assert result.primitive_id[i] == -1
        elif method == "occluded":
            assert not result[i]
        else:
            assert i not in result[0]
        expect_no_crash(lambda: getattr(scene_novalidation, method)(**kwargs))
        return
    expect_clean_error(lambda: getattr(scene, method)(**kwargs), arg)
    if label in ("nan inside", "inf inside", "-inf inside"):
        expect_no_crash(lambda: getattr(scene_novalidation, method)(**kwargs))
    else:
        expect_clean_error(lambda: getattr(scene_novalidation, method)(**kwargs), arg)


def test_zero_rays_give_empty_answers(scene):
    o = np.zeros((0, 3), np.float32)
    hits = scene.intersect(o, o)
    assert len(hits) == 0 and hits.t.shape == (0,) and hits.barycentrics.shape == (0, 2)
    assert scene.occluded(o, o).shape == (0,)
    ray, hits = scene.intersect_all(o, o)
    assert ray.shape == (0,) and len(hits) == 0
    assert len(scene.intersect(o, o, tmin=np.zeros(0, np.float32), tmax=np.zeros(0, np.float32))) == 0


def test_zero_triangles_build_and_miss(dev):
    empty = vkas.Scene(dev, np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32))
    o, d = some_rays(3)
    hits = empty.intersect(o, d)
    assert (hits.primitive_id == -1).all() and np.isinf(hits.t).all()
    assert not empty.occluded(o, d).any()
    soup = dev.build_bottom_level([vkas.Triangles(np.zeros((0, 3), np.float32))])
    assert soup.primitive_count == 0
    spheres = dev.build_bottom_level([vkas.Spheres(np.zeros((0, 3), np.float32), np.zeros(0, np.float32))])
    assert spheres.primitive_count == 0


# -- serialized blobs -----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def blob(dev):
    return dev.build_bottom_level([vkas.Triangles(V, F)]).serialize()


def blob_cases(blob):
    b = np.frombuffer(blob, np.uint8)
    return [
        ("float32 array", lambda: b[: len(b) // 4 * 4].view(np.float32)),
        ("every other byte", lambda: np.repeat(b, 2)[::2]),
        ("reversed memoryview", lambda: memoryview(bytes(blob))[::-1]),
        ("every other byte memoryview", lambda: memoryview(bytes(blob) * 2)[::2]),
        ("a list", lambda: list(blob[:100])),
        ("a string", lambda: "vkas"),
        ("empty", lambda: b""),
        ("the header only", lambda: blob[:64]),
        ("at an odd address", lambda: np.concatenate([np.zeros(1, np.uint8), b])[1:]),
    ]


def test_blobs(dev, dev_novalidation, blob):
    for label, make in blob_cases(blob):
        bad = make()
        if label == "at an odd address":  # uint8: every address is aligned; it must load
            assert dev.deserialize(bad).size > 0
            continue
        for d in (dev, dev_novalidation):
            with pytest.raises(ERRORS, match="blob"):
                d.deserialize(bad)
