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
    # the mesh is read at the first query, not when the intersector is made: its errors come then
    broken = vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=np.zeros((3, 3)), faces=np.array([[0, 1, 5]])))
    with pytest.raises(ValueError, match="^indices: face"):
        broken.intersects_any([[0, 0, -1]], [[0, 0, 1]])
    with pytest.raises(ValueError, match=r"^mesh.vertices: expected an \(n, 3\) or \(n, 2\) array"):
        vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=np.zeros((3, 4)), faces=[[0, 1, 2]])).intersects_first(
            [[0, 0, -1]], [[0, 0, 1]])
    with pytest.raises(ValueError, match="^mesh.faces: expected an"):
        vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=np.zeros((4, 3)), faces=[[0, 1, 2, 3]])).intersects_first(
            [[0, 0, -1]], [[0, 0, 1]])
    with pytest.raises(TypeError, match="^device"):
        vkas.trimesh.RayMeshIntersector(sphere, device="cpu")


# --- What trimesh needs of its intersector (issue 35): made inside Trimesh.__init__, read lazily, rebuilt when the
# mesh's hash changes. The meshes below expose what the adapter reads of a trimesh.Trimesh, without trimesh.

def _box(extents=(1.0, 1.0, 1.0)):
    """trimesh.creation.box's vertices and faces: an axis-aligned box centred at the origin, outward normals."""
    v = (np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64) - 0.5) * extents
    f = np.array([[1, 3, 0], [4, 1, 0], [0, 3, 2], [2, 4, 0], [1, 7, 3], [5, 1, 4], [5, 7, 1], [3, 7, 2], [6, 4, 2],
                  [2, 7, 6], [6, 5, 4], [7, 5, 6]], dtype=np.int64)
    return v, f


class TrackedMesh:
    """Like trimesh.Trimesh for the adapter: vertices, faces, and a hash that every edit changes; it counts reads."""

    def __init__(self, vertices, faces):
        self.ray = vkas.trimesh.RayMeshIntersector(self)  # as Trimesh.__init__: before the mesh has any data
        self._vertices = np.asarray(vertices, dtype=np.float64)
        self._faces = np.asarray(faces)
        self._version = 0
        self.reads = 0

    @property
    def vertices(self):
        self.reads += 1
        return self._vertices

    @vertices.setter
    def vertices(self, values):
        self._vertices = np.asarray(values, dtype=np.float64)
        self._version += 1

    @property
    def faces(self):
        return self._faces

    def apply_translation(self, translation):
        self.vertices = self._vertices + translation

    def contains(self, points):
        return self.ray.contains_points(points)

    def __hash__(self):
        return hash(("TrackedMesh", self._version))


class LazyBox:
    """Like a trimesh primitive: Trimesh.__init__ (which makes the intersector) runs before the attributes the
    vertices are computed from exist, and the hash is that of those attributes."""

    def __init__(self, extents, center=(0.0, 0.0, 0.0)):
        self.ray = vkas.trimesh.RayMeshIntersector(self)
        self.primitive = SimpleNamespace(extents=np.asarray(extents, dtype=np.float64),
                                         center=np.asarray(center, dtype=np.float64))

    @property
    def vertices(self):
        v, _ = _box(self.primitive.extents)
        return v + self.primitive.center

    @property
    def faces(self):
        _, f = _box()
        return f

    def __hash__(self):
        return hash((self.primitive.extents.tobytes(), self.primitive.center.tobytes()))


def test_made_before_the_mesh_exists():
    # a primitive's vertices come from attributes that Trimesh.__init__ has not set yet: nothing is read then
    class Unfinished:
        @property
        def vertices(self):
            raise AttributeError("'Box' object has no attribute 'primitive'")

        faces = vertices

    vkas.trimesh.RayMeshIntersector(Unfinished())  # no error
    vkas.trimesh.RayMeshIntersector(Unfinished(), scale_to_box=False, some_future_option=1)
    box = LazyBox([2, 2, 2])
    assert box.ray.intersects_any([[0, 0, -5]], [[0, 0, 1]]).tolist() == [True]
    assert box.ray.contains_points([[0, 0, 0], [0, 0, 1.5]]).tolist() == [True, False]


def test_rebuilds_when_the_hash_changes():
    # the documented use of issue 35: the intersector made once, the mesh moved afterwards
    m = TrackedMesh(*_box())
    assert m.reads == 0
    assert m.ray.intersects_any([[0, 0, -5]], [[0, 0, 1]]).tolist() == [True]
    assert m.contains([[0, 0, 0]]).tolist() == [True]
    reads = m.reads
    m.ray.intersects_first([[0, 0, -5]], [[0, 0, 1]])
    assert m.reads == reads  # same hash: the built scene is reused, the mesh not read again
    m.apply_translation([10, 0, 0])
    assert m.ray.intersects_any([[10, 0, -5], [0, 0, -5]], [[0, 0, 1], [0, 0, 1]]).tolist() == [True, False]
    assert m.contains([[10, 0, 0], [0, 0, 0]]).tolist() == [True, False]
    locations, index_ray, _ = m.ray.intersects_location([[10, 0, -5]], [[0, 0, 1]])
    np.testing.assert_allclose(locations, [[10, 0, -0.5], [10, 0, 0.5]])
    # a primitive whose attributes change
    box = LazyBox([2, 2, 2])
    assert box.ray.intersects_first([[0, 0, -5]], [[0, 0, 1]]) >= 0
    box.primitive.center = np.array([0.0, 5.0, 0.0])
    assert box.ray.intersects_first([[0, 0, -5], [0, 5, -5]], [[0, 0, 1], [0, 0, 1]])[0] == -1
    assert box.ray.contains_points([[0, 5, 0]]).tolist() == [True]


def test_unhashable_mesh_compares_contents():
    # without a hash of its own (SimpleNamespace has none), the contents are compared at every query
    v, f = _box()
    mesh = SimpleNamespace(vertices=v.copy(), faces=f)
    intersector = vkas.trimesh.RayMeshIntersector(mesh)
    assert intersector.intersects_any([[0, 0, -5]], [[0, 0, 1]]).tolist() == [True]
    scene = intersector._scene()
    assert intersector._scene() is scene  # unchanged: not rebuilt
    mesh.vertices += [0, 20, 0]  # edited in place
    assert intersector.intersects_any([[0, 0, -5], [0, 20, -5]], [[0, 0, 1], [0, 0, 1]]).tolist() == [False, True]
    mesh.faces = f[:, ::-1].copy()  # other faces, same vertices
    assert intersector._scene() is not scene


def test_2d_mesh():
    # trimesh allows (n, 2) vertices; they lie in the plane z = 0 (trimesh's util.stack_3D)
    square = SimpleNamespace(vertices=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64),
                             faces=np.array([[0, 1, 2], [0, 2, 3]]))
    intersector = vkas.trimesh.RayMeshIntersector(square)
    o = [[0.25, 0.5, 1], [0.75, 0.5, -1], [2, 2, 1]]
    d = [[0, 0, -1], [0, 0, 2], [0, 0, -1]]
    assert intersector.intersects_any(o, d).tolist() == [True, True, False]
    np.testing.assert_array_equal(intersector.intersects_first(o, d), [1, 0, -1])
    locations, index_ray, index_tri = intersector.intersects_location(o, d)
    np.testing.assert_allclose(locations, [[0.25, 0.5, 0], [0.75, 0.5, 0]])
    np.testing.assert_array_equal(index_ray, [0, 1])
    assert intersector.contains_points([[0.5, 0.5, 0.5]]).tolist() == [False]


@pytest.mark.parametrize("vertex_dtype", [np.float32, np.float64])
@pytest.mark.parametrize("face_dtype", [np.int64, np.int32, np.uint16, np.uint32, np.int8])
def test_dtypes(vertex_dtype, face_dtype):
    v, f = _box()
    first = vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=v.astype(vertex_dtype),
                                                            faces=f.astype(face_dtype)))
    assert first.intersects_first([[0.1, 0.2, -5]], [[0, 0, 1]]).tolist() == [8]  # as trimesh's box


def test_empty_mesh():
    for mesh in [SimpleNamespace(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64)),
                 SimpleNamespace(vertices=[], faces=[]),
                 SimpleNamespace(vertices=np.zeros((5, 2)), faces=np.zeros((0, 3), dtype=np.int64))]:
        intersector = vkas.trimesh.RayMeshIntersector(mesh)
        o, d = np.zeros((2, 3)), np.array([[0, 0, 1.0], [1, 0, 0]])
        assert intersector.intersects_first(o, d).tolist() == [-1, -1]
        assert intersector.intersects_any(o, d).tolist() == [False, False]
        index_tri, index_ray, locations = intersector.intersects_id(o, d, return_locations=True)
        assert index_tri.shape == index_ray.shape == (0,) and locations.shape == (0, 3)
        assert index_tri.dtype == index_ray.dtype == np.int64
        assert intersector.intersects_location(o, d, multiple_hits=False)[0].shape == (0, 3)
        assert intersector.contains_points(o).tolist() == [False, False]


def test_rays_vkas_would_reject_miss():
    # trimesh's intersectors answer "no hit" for rays with a zero, infinite or NaN direction or origin
    m = TrackedMesh(*_box())
    o = [[0, 0, -5], [0, 0, -5], [np.nan, 0, -5], [0, 0, -np.inf], [0, 0, -5], [0, 0, -5]]
    d = [[0, 0, 1], [0, 0, 0], [0, 0, 1], [0, 0, 1], [0, np.nan, 1], [0, 0, 1e39]]
    assert m.ray.intersects_any(o, d).tolist() == [True] + [False] * 5
    np.testing.assert_array_equal(m.ray.intersects_first(o, d), [8, -1, -1, -1, -1, -1])  # the diagonal: one of 3, 8
    index_tri, index_ray = m.ray.intersects_id(o, d)
    np.testing.assert_array_equal(index_ray, [0, 0])
    np.testing.assert_array_equal(m.ray.intersects_id(o, d, multiple_hits=False)[1], [0])
    assert m.contains([[0, 0, 0], [np.nan, 0, 0], [0, 0, 1e39]]).tolist() == [True, False, False]


def test_non_finite_vertices_make_their_triangles_inactive():
    # Embree ignores triangles with non-finite vertices; vkas makes them inactive (never hit)
    v, f = _box()
    v[0] = [np.nan, 0, 0]
    v[7] = [1e39, 0, 0]  # not finite in float32
    intersector = vkas.trimesh.RayMeshIntersector(SimpleNamespace(vertices=v, faces=f))
    used = np.isin(f, [0, 7]).any(axis=1)
    o = np.array([[0.3, 0.3, -5], [-0.3, -0.3, -5], [0.3, -0.3, 5], [-0.3, 0.3, 5]])
    d = np.array([[0, 0, 1], [0, 0, 1], [0, 0, -1], [0, 0, -1]])
    index_tri, index_ray = intersector.intersects_id(o, d)
    assert len(index_tri) > 0 and not used[index_tri].any()


def test_copy_pickle_and_arguments():
    import copy
    import pickle

    m = TrackedMesh(*_box())
    m.ray = vkas.trimesh.RayMeshIntersector(m, scale_to_box=False, extra="kept")
    assert m.ray.scale_to_box is False and m.ray.kwargs == {"extra": "kept"}
    m.ray.intersects_any([[0, 0, -5]], [[0, 0, 1]])
    for other in [copy.copy(m.ray), copy.deepcopy(m.ray)]:
        assert other.mesh is m and other.scale_to_box is False and other.kwargs == {"extra": "kept"}
        assert other._built is None  # the scene is not copied: built again at the first query
        assert other.intersects_any([[0, 0, -5]], [[0, 0, 1]]).tolist() == [True]
    clone = pickle.loads(pickle.dumps(m))
    assert clone.ray.mesh is clone and clone.ray._built is None
    clone.apply_translation([0, 0, 100])
    assert clone.ray.intersects_any([[0, 0, 95]], [[0, 0, 1]]).tolist() == [True]
    assert m.ray.intersects_any([[0, 0, 95]], [[0, 0, 1]]).tolist() == [False]
    dev = vkas.Device(validation=True, threads=1)
    assert vkas.trimesh.RayMeshIntersector(m, dev).device is dev
    assert vkas.trimesh.RayMeshIntersector(m).device is vkas.trimesh.RayMeshIntersector(m).device  # shared


def test_spec_exact_differences():
    # 1. an origin on a face: no hit at t = 0 (a triangle hit needs tmin < t, tmin = 0); Embree reports it
    m = TrackedMesh(*_box())
    index_tri, index_ray = m.ray.intersects_id([[0.1, 0.2, 0.5]], [[0, 0, -1]])
    assert len(index_tri) == 1  # the far face (z = -0.5) only; Embree also gives the face the ray starts on
    assert m.ray.intersects_any([[0.1, 0.2, 0.5]], [[0, 0, 1]]).tolist() == [False]
    # 2. a ray grazing along a face, in its plane, never crosses the surface: the tie-break of the watertight test
    # gives it the edges on some sides of the box and not on the others
    o = [[0.5, 0, 5], [-0.5, 0, 5], [0, 0.5, 5], [0, -0.5, 5]]
    d = np.tile([[0, 0, -1.0]], (4, 1))
    grazing = m.ray.intersects_any(o, d)
    assert grazing.any() and not grazing.all()


def test_install_into_a_trimesh_like_module(monkeypatch):
    # install() replaces trimesh.ray.ray_pyembree and sets has_embree; uninstall() puts them back. A stand-in for
    # trimesh here (python/tests/test_trimesh_suite.py runs trimesh's own tests with it installed)
    import sys
    import types

    trimesh = types.ModuleType("trimesh")
    ray = types.ModuleType("trimesh.ray")
    ray.has_embree = False
    ray.ray_pyembree = "trimesh's ExceptionWrapper"
    trimesh.ray = ray
    monkeypatch.setitem(sys.modules, "trimesh", trimesh)
    monkeypatch.setitem(sys.modules, "trimesh.ray", ray)
    monkeypatch.delitem(sys.modules, "trimesh.ray.ray_pyembree", raising=False)
    module = vkas.trimesh.install()
    try:
        assert ray.has_embree is True and ray.ray_pyembree is module
        assert sys.modules["trimesh.ray.ray_pyembree"] is module
        assert module.RayMeshIntersector is vkas.trimesh.RayMeshIntersector
        from trimesh.ray.ray_pyembree import RayMeshIntersector
        assert RayMeshIntersector is vkas.trimesh.RayMeshIntersector
        assert vkas.trimesh.install() is not None  # again: harmless
    finally:
        vkas.trimesh.uninstall()
    assert ray.has_embree is False and ray.ray_pyembree == "trimesh's ExceptionWrapper"
    assert "trimesh.ray.ray_pyembree" not in sys.modules
