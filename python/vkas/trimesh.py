"""A trimesh-compatible ray intersector over vkas.

trimesh's ray queries (``mesh.ray``, ``trimesh.ray.ray_triangle.RayMeshIntersector``,
``trimesh.ray.ray_pyembree.RayMeshIntersector``) have four documented methods; this class has the same names,
arguments and return shapes, so code written for trimesh switches by changing the line that makes the
intersector::

    intersector = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)   # before
    intersector = vkas.trimesh.RayMeshIntersector(mesh)               # after

or, for every mesh trimesh makes from then on, ``vkas.trimesh.install()`` (trimesh then takes it for its embree
intersector, ``trimesh.ray.ray_pyembree.RayMeshIntersector``).

It needs only an object with ``.vertices`` (n, 3) or (n, 2) and ``.faces`` (m, 3) (a ``trimesh.Trimesh``, or
anything alike); trimesh itself is not imported. As trimesh's own intersectors, it reads the mesh lazily, at the
first query, and again whenever the mesh changes (keyed on ``hash(mesh)``, which trimesh changes on every edit), so it
can be made inside ``Trimesh.__init__`` (before the mesh has vertices, or, for a primitive, before the attributes its
vertices come from) and stays right after ``apply_translation`` and the like.

Unlike trimesh's intersectors, every hit is exact and found once: a ray through a shared edge or vertex hits exactly
one of the triangles there, multiple hits come from one traversal (no re-cast from an offset origin, so none is lost
or doubled), and results do not depend on the thread count. Directions need not be unit length. Hits of one ray are
in order of distance; the rays' hits are in ray order (trimesh specifies neither). Two differences from Embree's
answers follow from the specification (docs/PYTHON.md, "The trimesh adapter"): a ray whose origin lies on a face
does not hit it at t = 0 (a triangle hit needs tmin < t, tmin = 0), and a ray that grazes along a face or an edge
without crossing the surface is counted by the watertight tie-break on some sides only.
"""

import sys
import threading
import types

import numpy as np

from . import Device, Scene

__all__ = ["RayMeshIntersector", "install", "uninstall"]

_default_device = None
_default_device_lock = threading.Lock()


def _shared_device():
    """The device of intersectors made without one: one for the process, validation off, made at first use."""
    global _default_device
    with _default_device_lock:
        if _default_device is None:
            _default_device = Device(validation=False)
        return _default_device


def _as_rays(ray_origins, ray_directions):
    o = np.asarray(ray_origins, dtype=np.float64)
    d = np.asarray(ray_directions, dtype=np.float64)
    if o.ndim != 2 or o.shape[1] != 3:
        raise ValueError(f"ray_origins: expected an (n, 3) array, got shape {o.shape}")
    if d.shape != o.shape:
        raise ValueError(f"ray_directions: expected an (n, 3) array like ray_origins {o.shape}, got shape {d.shape}")
    return o, d


def _traceable(o, d):
    """The rays vkas can trace: finite origin and direction, direction not zero (in float32). Others miss, as in
    trimesh's intersectors (vkas itself rejects non-finite rays)."""
    with np.errstate(over="ignore", invalid="ignore"):
        o32 = o.astype(np.float32)
        d32 = d.astype(np.float32)
        ok = np.isfinite(o32).all(axis=1) & np.isfinite(d32).all(axis=1) & (d32 != 0).any(axis=1)
    return ok


def _mesh_arrays(mesh):
    """mesh.vertices as (n, 3) float32 and mesh.faces as (m, 3) integers, as vkas traces them, and the vertices as
    (n, 3) float64 (for the locations).

    (n, 2) vertices lie in the plane z = 0 (trimesh's convention, util.stack_3D). A vertex with a coordinate that is
    not finite (or not finite in float32) makes the triangles that use it inactive: they are never hit, as Embree
    ignores such triangles (vkas's rule: a NaN x marks the vertex inactive)."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    if faces.size == 0:
        return None, None, None
    if vertices.ndim != 2 or vertices.shape[1] not in (2, 3):
        raise ValueError(f"mesh.vertices: expected an (n, 3) or (n, 2) array, got shape {vertices.shape}")
    if faces.ndim == 1 and faces.size % 3 == 0:
        faces = faces.reshape(-1, 3)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"mesh.faces: expected an (m, 3) integer array of triangles, got shape {faces.shape}")
    if vertices.shape[1] == 2:
        vertices = np.column_stack((vertices, np.zeros(len(vertices))))
    with np.errstate(over="ignore", invalid="ignore"):
        v32 = np.ascontiguousarray(vertices, dtype=np.float32)
        bad = ~np.isfinite(v32).all(axis=1)
    if bad.any():
        v32[bad] = 0
        v32[bad, 0] = np.nan
    return v32, faces, vertices


class RayMeshIntersector:
    """Ray queries on a mesh with trimesh's method names and return shapes.

    mesh: an object with ``.vertices`` (n, 3) or (n, 2) float and ``.faces`` (m, 3) int (a trimesh.Trimesh, a
    primitive, anything alike). Nothing of it is read when the intersector is made: the first query copies it into a
    vkas bottom level, and a query rebuilds that when the mesh has changed since. "Changed" is ``hash(mesh)``
    (trimesh's hash of its data, which every edit changes) when the mesh's class defines ``__hash__``, else the
    contents of vertices and faces (compared at every query). (n, 2) vertices lie in the plane z = 0.
    device: the vkas.Device to use (default: one shared by such intersectors, validation off, made at first use).
    scale_to_box, kwargs: trimesh's arguments (``trimesh.ray.ray_pyembree.RayMeshIntersector(geometry,
    scale_to_box=True)``), accepted and kept (``scale_to_box``, ``kwargs``); they change nothing: vkas traces the
    mesh's float32 coordinates as a Vulkan implementation would, and its watertight test has no epsilon to tune.
    """

    def __init__(self, mesh, device=None, scale_to_box=True, **kwargs):
        if device is not None and not isinstance(device, Device):
            raise TypeError(f"device: expected a vkas.Device or None, got {type(device).__name__}")
        self.mesh = mesh
        self._device = device
        self.scale_to_box = scale_to_box
        self.kwargs = kwargs
        self._lock = threading.Lock()
        self._built = None  # (key, scene or None for a mesh without triangles, float32 vertices, faces, float64 ones)

    @property
    def device(self):
        """The vkas.Device the intersector traces with."""
        return self._device if self._device is not None else _shared_device()

    def __repr__(self):
        return "vkas.trimesh.RayMeshIntersector"

    # -- the mesh, read lazily -------------------------------------------------------------------------------------

    def _key(self):
        """What identifies the mesh's current state: hash(mesh) if its class defines a hash, else None (compare the
        contents)."""
        cls_hash = type(self.mesh).__hash__
        if cls_hash is None or cls_hash is object.__hash__:
            return None
        try:
            return hash(self.mesh)
        except TypeError:
            return None

    def _scene(self):
        """The vkas.Scene of the mesh as it is now (None for a mesh without triangles), built or rebuilt here."""
        return self._state()[1]

    def _state(self):
        """(key, scene, float32 vertices, faces, float64 vertices) of the mesh as it is now, built or rebuilt here."""
        with self._lock:
            key = self._key()
            built = self._built
            if key is not None:
                if built is not None and built[0] == key:
                    return built
                v, f, v64 = _mesh_arrays(self.mesh)
            else:
                v, f, v64 = _mesh_arrays(self.mesh)
                if built is not None and built[0] is None and _same(v, built[2]) and _same(f, built[3]):
                    return built
            self._built = None
            scene = None if v is None else Scene(self.device, v, f)
            if key is None and v is not None:
                # keep what it was built from, to compare at the next query (the mesh's arrays may change in place)
                v, f, v64 = v.copy(), np.array(f, copy=True), v64.copy()
            self._built = (key, scene, v, f, v64)
            return self._built

    # -- queries ---------------------------------------------------------------------------------------------------

    def intersects_id(self, ray_origins, ray_directions, multiple_hits=True, max_hits=100, return_locations=False):
        """Triangles hit by each ray.

        Returns index_tri (m,) int64 (indexes of mesh.faces), index_ray (m,) int64 and, with return_locations,
        locations (m, 3) float64. With multiple_hits every hit along each ray (at most max_hits a ray, the
        closest), else only the first (closest) one.
        """
        o, d = _as_rays(ray_origins, ray_directions)
        state = self._state()
        scene = state[1]
        ok = _traceable(o, d)
        if scene is None or not ok.any():
            empty = np.zeros(0, dtype=np.int64)
            return (empty, empty.copy(), np.zeros((0, 3))) if return_locations else (empty, empty.copy())
        rays = np.flatnonzero(ok)
        if multiple_hits:
            sub_ray, hits = scene.intersect_all(o[rays], d[rays], max_hits=int(max_hits))
            index_ray = rays[sub_ray].astype(np.int64)
            index_tri = hits.primitive_id.astype(np.int64)
            t = hits.t
        else:
            hits = scene.intersect(o[rays], d[rays])
            hit = np.flatnonzero(hits.hit)
            index_ray = rays[hit].astype(np.int64)
            index_tri = hits.primitive_id[hit].astype(np.int64)
            t = hits.t[hit]
        if return_locations:
            return index_tri, index_ray, _locations(state, o[index_ray], d[index_ray], index_tri, t)
        return index_tri, index_ray

    def intersects_location(self, ray_origins, ray_directions, multiple_hits=True):
        """Where the rays hit: locations (m, 3) float64, index_ray (m,) int64, index_tri (m,) int64."""
        index_tri, index_ray, locations = self.intersects_id(ray_origins, ray_directions,
                                                             multiple_hits=multiple_hits, return_locations=True)
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins, ray_directions):
        """The index of the first (closest) triangle each ray hits, -1 for a miss: (n,) int64."""
        o, d = _as_rays(ray_origins, ray_directions)
        first = np.full(len(o), -1, dtype=np.int64)
        scene = self._scene()
        ok = _traceable(o, d)
        if scene is not None and ok.any():
            first[ok] = scene.intersect(o[ok], d[ok]).primitive_id
        return first

    def intersects_any(self, ray_origins, ray_directions):
        """Whether each ray hits the mesh: (n,) bool."""
        o, d = _as_rays(ray_origins, ray_directions)
        hit = np.zeros(len(o), dtype=bool)
        scene = self._scene()
        ok = _traceable(o, d)
        if scene is not None and ok.any():
            hit[ok] = scene.occluded(o[ok], d[ok])
        return hit

    def contains_points(self, points):
        """Whether each point is inside the (closed) mesh: the parity of the hits along one ray from it.

        Points on the surface give an undefined answer, as in trimesh."""
        p = np.asarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points: expected an (n, 3) array, got shape {p.shape}")
        inside = np.zeros(len(p), dtype=bool)
        scene = self._scene()
        with np.errstate(over="ignore", invalid="ignore"):
            ok = np.isfinite(p.astype(np.float32)).all(axis=1)
        if scene is None or not ok.any():
            return inside
        direction = np.array([0.4395064455, 0.617598629942, 0.652231566745])
        q = p[ok]
        index_ray, _ = scene.intersect_all(q, np.broadcast_to(direction, q.shape))
        inside[ok] = np.bincount(index_ray, minlength=len(q)) % 2 == 1
        return inside

    # -- copies and pickles: the mesh and the arguments, never the built scene (as trimesh's intersectors) ----------

    def __getstate__(self):
        return {"mesh": self.mesh, "device": self._device, "scale_to_box": self.scale_to_box, "kwargs": self.kwargs}

    def __setstate__(self, state):
        self.__init__(state["mesh"], device=state["device"], scale_to_box=state["scale_to_box"], **state["kwargs"])

    def __copy__(self):
        return RayMeshIntersector(self.mesh, device=self._device, scale_to_box=self.scale_to_box, **self.kwargs)

    def __deepcopy__(self, memo):
        return self.__copy__()


def _locations(state, o, d, index_tri, t):
    """origin + t * direction in float64, t the distance to the hit triangle's plane computed in float64 from
    the mesh's own vertices (as trimesh's intersectors do), or vkas's float32 t where the ray is within about
    1e-6 rad of the plane (or the plane's normal is not finite)."""
    t = t.astype(np.float64)
    _, _, _, faces, v64 = state
    tri = v64[faces[index_tri]]
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        dn = np.einsum("ij,ij->i", d, n)
        plane = np.einsum("ij,ij->i", tri[:, 0] - o, n) / dn
        good = (np.abs(dn) > 1e-6 * np.linalg.norm(d, axis=1) * np.linalg.norm(n, axis=1)) & np.isfinite(plane)
    t[good] = plane[good]
    return o + d * t[:, None]


def _same(a, b):
    if a is None or b is None:
        return a is None and b is None
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    return np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


# -- trimesh's embree intersector -----------------------------------------------------------------------------------

_saved = None


def install():
    """Make trimesh use vkas for every mesh it makes from now on: imports trimesh, puts a module
    ``trimesh.ray.ray_pyembree`` whose ``RayMeshIntersector`` is this class in the place of trimesh's (in
    ``trimesh.ray`` and ``sys.modules``), and sets ``trimesh.ray.has_embree = True``, so that ``Trimesh.__init__``
    (``use_embree=True``, its default) makes ``mesh.ray`` a vkas.trimesh.RayMeshIntersector. Meshes made before keep
    their intersector. Returns the stand-in module. ``uninstall()`` puts trimesh's back."""
    global _saved
    import trimesh.ray as ray

    if _saved is None:
        _saved = (getattr(ray, "has_embree", False), getattr(ray, "ray_pyembree", None),
                  sys.modules.get("trimesh.ray.ray_pyembree"))
    module = types.ModuleType("trimesh.ray.ray_pyembree",
                              "vkas.trimesh.RayMeshIntersector standing in for trimesh's embree intersector "
                              "(vkas.trimesh.install()).")
    module.RayMeshIntersector = RayMeshIntersector
    module.__file__ = __file__
    ray.ray_pyembree = module
    ray.has_embree = True
    sys.modules["trimesh.ray.ray_pyembree"] = module
    return module


def uninstall():
    """Undo install(): trimesh's own ray_pyembree (or its absence) and has_embree again."""
    global _saved
    if _saved is None:
        return
    import trimesh.ray as ray

    has_embree, attribute, module = _saved
    ray.has_embree = has_embree
    if attribute is not None:
        ray.ray_pyembree = attribute
    if module is not None:
        sys.modules["trimesh.ray.ray_pyembree"] = module
    else:
        sys.modules.pop("trimesh.ray.ray_pyembree", None)
    _saved = None
