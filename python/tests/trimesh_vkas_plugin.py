"""A pytest plugin that runs trimesh's own tests with vkas.trimesh.RayMeshIntersector as trimesh's embree intersector.

test_trimesh_suite.py loads it into the pytest it runs on a trimesh checkout (``-p trimesh_vkas_plugin``): before
trimesh's tests import trimesh, it calls ``vkas.trimesh.install()``, so every ``Trimesh`` (``use_embree=True``, the
default) gets ``mesh.ray = vkas.trimesh.RayMeshIntersector(mesh)`` and ``trimesh.ray.ray_pyembree.RayMeshIntersector``
is vkas's.

When the ``embreex`` package is not installed, it also puts a stand-in module ``embreex`` (only ``__version__``,
"4.0.0+vkas-stand-in") in ``sys.modules``: trimesh's ``test_ray.py::test_embree_duplicate_hits`` returns before its
checks unless ``from embreex import __version__`` gives a version >= 4, and with the stand-in it runs them on vkas's
intersector. trimesh's own ``ray_pyembree`` still fails to import (the stand-in has no ``rtcore_scene``), so nothing
of Embree is used.
"""

import importlib.util
import sys
import types

import vkas
import vkas.trimesh


def pytest_configure(config):
    if importlib.util.find_spec("embreex") is None:
        stand_in = types.ModuleType("embreex", "A stand-in for embreex (python/tests/trimesh_vkas_plugin.py).")
        stand_in.__version__ = "4.0.0+vkas-stand-in"
        sys.modules["embreex"] = stand_in
    vkas.trimesh.install()


def pytest_report_header(config):
    import trimesh

    intersector = type(trimesh.Trimesh().ray)
    return [f"trimesh {trimesh.__version__} from {trimesh.__file__}",
            f"mesh.ray: {intersector.__module__}.{intersector.__qualname__} (vkas {vkas.__version__} from "
            f"{vkas.__file__})"]
