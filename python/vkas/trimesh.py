"""A trimesh-compatible ray intersector over vkas.

trimesh's ray queries (``mesh.ray``, ``trimesh.ray.ray_triangle.RayMeshIntersector``,
``trimesh.ray.ray_pyembree.RayMeshIntersector``) have four documented methods; this class has the same names,
arguments and return shapes, so code written for trimesh switches by changing the line that makes the
intersector::

    intersector = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)   # before
    intersector = vkas.trimesh.RayMeshIntersector(mesh)               # after

It needs only an object with ``.vertices`` (n, 3) and ``.faces`` (m, 3) (a ``trimesh.Trimesh``, or anything alike);
trimesh itself is not imported. Unlike trimesh's intersectors, every hit is exact and found once: a ray through a
shared edge or vertex hits exactly one of the triangles there, multiple hits come from one traversal (no
re-cast from an offset origin, so none is lost or doubled), and results do not depend on the thread count.
Directions need not be unit length. Hits at the ray origin (t = 0) are not reported. Hits of one ray are in
order of distance; the rays' hits are in ray order (trimesh specifies neither).
"""

import numpy as np

from . import Device, Scene

__all__ = ["RayMeshIntersector"]


def _as_rays(ray_origins, ray_directions):
    o = np.asarray(ray_origins, dtype=np.float64)
    d = np.asarray(ray_directions, dtype=np.float64)
    if o.ndim != 2 or o.shape[1] != 3:
        raise ValueError(f"ray_origins: expected an (n, 3) array, got shape {o.shape}")
    if d.shape != o.shape:
        raise ValueError(f"ray_directions: expected an (n, 3) array like ray_origins {o.shape}, got shape {d.shape}")
    return o, d


class RayMeshIntersector:
    """Ray queries on a mesh with trimesh's method names and return shapes.

    mesh: an object with ``.vertices`` (n, 3) float and ``.faces`` (m, 3) int. The mesh is copied into a vkas
    bottom level when the intersector is made: later changes to the mesh are not seen (make a new intersector).
    device: the vkas.Device to use (a new one with validation off by default).
    """

    def __init__(self, mesh, device=None):
        self.mesh = mesh
        self.device = device if device is not None else Device(validation=False)
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        faces = np.asarray(mesh.faces)
        self._scene = Scene(self.device, vertices, faces.reshape(-1, 3))

    def __repr__(self):
        return "vkas.trimesh.RayMeshIntersector"

    def intersects_id(self, ray_origins, ray_directions, multiple_hits=True, max_hits=100, return_locations=False):
        """Triangles hit by each ray.

        Returns index_tri (m,) int64 (indexes of mesh.faces), index_ray (m,) int64 and, with return_locations,
        locations (m, 3) float64. With multiple_hits every hit along each ray (at most max_hits a ray, the
        closest), else only the first (closest) one.
        """
        o, d = _as_rays(ray_origins, ray_directions)
        if multiple_hits:
            index_ray, hits = self._scene.intersect_all(o, d, max_hits=int(max_hits))
            index_tri = hits.primitive_id.astype(np.int64)
            t = hits.t
        else:
            hits = self._scene.intersect(o, d)
            index_ray = np.flatnonzero(hits.hit).astype(np.int64)
            index_tri = hits.primitive_id[index_ray].astype(np.int64)
            t = hits.t[index_ray]
        if return_locations:
            locations = o[index_ray] + d[index_ray] * t.astype(np.float64)[:, None]
            return index_tri, index_ray, locations
        return index_tri, index_ray

    def intersects_location(self, ray_origins, ray_directions, multiple_hits=True):
        """Where the rays hit: locations (m, 3) float64, index_ray (m,) int64, index_tri (m,) int64."""
        index_tri, index_ray, locations = self.intersects_id(ray_origins, ray_directions,
                                                             multiple_hits=multiple_hits, return_locations=True)
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins, ray_directions):
        """The index of the first (closest) triangle each ray hits, -1 for a miss: (n,) int64."""
        o, d = _as_rays(ray_origins, ray_directions)
        return self._scene.intersect(o, d).primitive_id.astype(np.int64)

    def intersects_any(self, ray_origins, ray_directions):
        """Whether each ray hits the mesh: (n,) bool."""
        o, d = _as_rays(ray_origins, ray_directions)
        return self._scene.occluded(o, d)

    def contains_points(self, points):
        """Whether each point is inside the (closed) mesh: the parity of the hits along one ray from it.

        Points on the surface give an undefined answer, as in trimesh."""
        p = np.asarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points: expected an (n, 3) array, got shape {p.shape}")
        direction = np.array([0.4395064455, 0.617598629942, 0.652231566745])
        index_ray, _ = self._scene.intersect_all(p, np.broadcast_to(direction, p.shape))
        return np.bincount(index_ray, minlength=len(p)) % 2 == 1
