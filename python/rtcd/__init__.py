"""rtcd: ray-traced narrow-phase collision detection for concave meshes.

Meshes and shapes (Mesh, Shape, gen), the narrow phase (NarrowPhase, query,
backends, knobs), the references it is judged by (oracle), and the
experiments (validate, Simulation, run). Arrays are NumPy arrays.
"""
import sys as _sys

from . import _rtcd
from ._rtcd import *  # noqa: F401,F403
from ._rtcd import __version__, gen, oracle  # noqa: F401

# The submodules import as rtcd.oracle and rtcd.gen, and everything names
# itself from the package rather than from the extension module.
_sys.modules[__name__ + ".oracle"] = oracle
_sys.modules[__name__ + ".gen"] = gen
for _module in (_rtcd, oracle, gen):
    for _value in vars(_module).values():
        if isinstance(_value, type) and getattr(_value, "__module__", "").startswith("rtcd._rtcd"):
            _value.__module__ = __name__ if _module is _rtcd else _module.__name__.replace("_rtcd.", "")
del _module, _value, _sys
