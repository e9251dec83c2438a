"""radmesh: exact-geometry meshing and radiosity, from Python.

    import radmesh
    scene = radmesh.read_scene("cornell_box.obj")
    result = radmesh.solve(scene, method="hierarchical", epsilon=0.01)
    result.vertex_radiosity        # (n, 3) numpy array, no copy
    result.patch_means()           # (patches, 3)
    result.summary()["solver"]     # the dict summary.json holds
    result.write("out")            # the files `radmesh run` writes

Options go by the radmesh program's names with '_' for '-' (max_edge,
display_tolerance, epsilon, ...); radmesh.methods(), solve_options() and
meshing_options() (and scene_options(), which read_scene takes) list them with their units and ranges. Errors are
radmesh.InputError (a ValueError), GeometryError, NumericalError and IoError
(an OSError), all radmesh.Error, with the file, line and value in the message.

The module itself does not load VTK (it runs inside ParaView's Python);
Result.write and resuming the pixmap method load radmesh._files, which does.
"""

import json as _json
import os as _os
import warnings as _warnings

from . import _core
from ._core import (Error, GeometryError, InputError, IoError, Mesh, NumericalError, Result, Scene, mesh,
                    meshing_options, methods, quality, scene_options, solve_options)

__version__ = _core.__version__

__all__ = ["Error", "GeometryError", "InputError", "IoError", "Mesh", "NumericalError", "Result", "Scene", "mesh",
           "meshing_options", "methods", "quality", "read_scene", "scene_options", "solve", "solve_options"]


def read_scene(path, **scene_options):
    """Reads a scene file (a str or os.PathLike) of any format `radmesh run` reads."""
    return _core.read_scene(_os.fspath(path), **scene_options)


def solve(scene, method=None, progress=None, resume=None, preset="default", **options):
    """Meshes `scene` as `method` recommends (meshing options on top) and solves it.

    progress: called as progress(phase, fraction) from this thread, at most
    ten times a second (tqdm works). Ctrl-C stops the solve within about a
    second and raises KeyboardInterrupt; nothing is kept. resume: an output
    folder where a pixmap run saved its state (Result.write) to continue from.
    preset: "draft", "default" or "fine", the options of the method's preset
    (methods()[k]["presets"]) where `options` does not name them.
    """
    if method is None:
        method = methods()[0]["name"]
    if resume is not None:
        from . import _files  # noqa: F401  (the pixmap state is a set of VTK images)
    return _core.solve(scene, method, progress, None if resume is None else _os.fspath(resume), preset, **options)


def _summary(self):
    """The document summary.json holds, as a dict."""
    return _json.loads(self.summary_text())


def _write(self, out_dir, png=True):
    """Writes the files `radmesh run` writes into out_dir, all or none; returns their paths.

    png: radiosity.png too, where a display can be had (else a warning says why not).
    """
    from . import _files
    written, notes = _files.write(self, _os.fspath(out_dir), png)
    for note in notes:
        _warnings.warn(note, stacklevel=2)
    return written


Result.summary = _summary
Result.write = _write
