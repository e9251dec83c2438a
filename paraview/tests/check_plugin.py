"""pvbatch check of the ParaView plugin: both proxies on the Cornell box give
radiosity.vtu's arrays, value for value. Run by paraview/tests/run_pvbatch.sh:

    pvbatch check_plugin.py PLUGIN SCENE CLI_OUT_DIR [SCREENSHOT.png]

CLI_OUT_DIR holds `radmesh run SCENE --epsilon 0.01 --max-edge 150`'s files.
"""

import os
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import (Clip, ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, LoadPlugin, OpenDataFile,
                             ResetCamera, SaveScreenshot, Show, TrivialProducer)
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

import radmesh

# Debian 12's ParaView 5.11 loads Python plugins with inspect.getargspec,
# which Python 3.11 removed; getfullargspec answers what it asks (.args).
import inspect  # noqa: E402
if not hasattr(inspect, "getargspec"):
    inspect.getargspec = inspect.getfullargspec

plugin, scene_path, cli_dir = sys.argv[1:4]
screenshot = sys.argv[4] if len(sys.argv) > 4 else None
LoadPlugin(plugin, ns=globals())
failures = []


def arrays(proxy):
    proxy.UpdatePipeline()
    data = dsa.WrapDataObject(servermanager.Fetch(proxy))
    out = {("points", ""): np.asarray(data.Points)}
    for where, group in (("point", data.PointData), ("cell", data.CellData)):
        for name in group.keys():
            out[(where, name)] = np.asarray(group[name])
    return out


def compare(what, got, want):
    if set(got) != set(want):
        failures.append(f"{what}: arrays {sorted(got)} against radiosity.vtu's {sorted(want)}")
        return
    for key in want:
        if got[key].shape != want[key].shape or not np.array_equal(got[key], want[key]):
            failures.append(f"{what}: {key} differs from radiosity.vtu's")
    print(f"{what}: {len(want)} arrays equal to radiosity.vtu's")


reference = arrays(OpenDataFile(os.path.join(cli_dir, "radiosity.vtu")))

source = radmeshScene(FileName=scene_path, Method="hierarchical", Epsilon=0.01, MaxEdge=150.0)
compare("radmesh Scene", arrays(source), reference)

# The same patches as polygons with reflectance and emission cell arrays.
scene = radmesh.read_scene(scene_path)
offsets, indices = scene.patches
poly = vtkPolyData()
points = vtkPoints()
points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(scene.vertices), deep=1))
poly.SetPoints(points)
cells = vtkCellArray()
cells.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets.astype(np.int64).copy(), deep=1),
              numpy_support.numpy_to_vtkIdTypeArray(indices.astype(np.int64).copy(), deep=1))
poly.SetPolys(cells)
for name in ("reflectance", "emission"):
    values = np.array([scene.materials[m][name] for m in scene.patch_materials])
    a = numpy_support.numpy_to_vtk(values, deep=1)
    a.SetName(name)
    poly.GetCellData().AddArray(a)
producer = TrivialProducer()
producer.GetClientSideObject().SetOutput(poly)
# --preset draft is --epsilon 0.01: the same run.
lit = radmeshRadiosity(Input=producer, Method="hierarchical", Preset="draft", MaxEdge=150.0)
compare("radmesh Radiosity", arrays(lit), reference)

if screenshot:
    # The box from its open side, its front wall (z = 0) clipped away.
    clip = Clip(Input=source)
    clip.ClipType = "Plane"
    clip.ClipType.Origin = [0, 0, 1]
    clip.ClipType.Normal = [0, 0, 1]
    clip.Invert = 0
    view = GetActiveViewOrCreate("RenderView")
    display = Show(clip, view)
    ColorBy(display, ("POINTS", "radiosity", "Magnitude"))
    lut = GetColorTransferFunction("radiosity")
    lut.ApplyPreset("Inferno (matplotlib)", True)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, 1.2)  # the walls' range; the light saturates
    view.CameraPosition = [278, 273, -800]
    view.CameraFocalPoint = [278, 273, 280]
    view.CameraViewUp = [0, 1, 0]
    view.OrientationAxesVisibility = 0
    ResetCamera()
    SaveScreenshot(screenshot, view, ImageResolution=[480, 480])
    print("screenshot:", screenshot)

if failures:
    print("\n".join(failures))
    sys.exit(1)
