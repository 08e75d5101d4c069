"""vkas: watertight, deterministic ray casting on numpy arrays.

The Python binding of vkas, an implementation of Vulkan's acceleration-structure host commands and host ray queries
on the CPU. Rays through shared edges and vertices hit exactly once (the specification's watertight test), and
results are bit-identical whatever the number of threads. See docs/PYTHON.md.

    import numpy as np, vkas
    dev = vkas.Device()
    scene = vkas.Scene(dev, vertices, faces)
    hits = scene.intersect(origins, directions)      # hits.t: inf on a miss
"""

# The package's modules (each imports only what it uses): _checks (argument checks and conversions), _flags (RayFlags,
# InstanceFlags, flag bits and record formats), _geometry (Triangles, Spheres), _structures (BottomLevel, Instance),
# _top_level (TopLevel, Hits), _device (Device), _scene (Scene), _errors (ValidationError); _core is the extension.
# The public classes keep __module__ "vkas", so pickles and reprs name them as before the split; _load_bottom and
# _load_top are imported here because pickles of structures name them vkas._load_bottom and vkas._load_top.
from ._device import Device
from ._errors import ValidationError
from ._flags import InstanceFlags, RayFlags
from ._geometry import Spheres, Triangles
from ._scene import Scene
from ._structures import BottomLevel, Instance, _load_bottom
from ._top_level import Hits, TopLevel, _load_top

__version__ = "0.1.0"

__all__ = [
    "BottomLevel",
    "Device",
    "Hits",
    "Instance",
    "InstanceFlags",
    "RayFlags",
    "Scene",
    "Spheres",
    "TopLevel",
    "Triangles",
    "ValidationError",
]

