"""radmesh in ParaView (5.11): a source that solves a scene file, and a filter
that lights any polygonal data. Load it with Tools > Manage Plugins > Load New
(this file), or LoadPlugin("radmesh_paraview.py", ns=globals()) in pvpython or
pvbatch; the radmesh Python module must be importable (PYTHONPATH). Debian 12's
ParaView 5.11 loads no Python plugin under Python 3.11 until, in its Python
Shell or script, `import inspect; inspect.getargspec = inspect.getfullargspec`.

Both output the solved mesh with the arrays of radmesh's radiosity.vtu: point
array "radiosity" (RGB), cell arrays "radiosity", "patch_id", "area",
"min_angle", "aspect_ratio", "reflectance", "emission" and the method's own.
The method and its options are properties made from radmesh.methods(), with
their ranges; an option is passed on only when it differs from its default.

The filter reads the input's cell arrays "reflectance" (1 or 3 components,
each in [0, 1)) and "emission" (1 or 3 components, radiant exitance, >= 0;
none: nothing emits). Each polygon is one patch; polygons with equal values
share a material.
"""

import numpy as np
from paraview.util.vtkAlgorithm import VTKPythonAlgorithmBase, smdomain, smhint, smproperty, smproxy
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import VTK_TRIANGLE, vtkCellArray, vtkPolyData, vtkUnstructuredGrid

import radmesh

_KINDS = {"real": "DoubleVectorProperty", "integer": "IntVectorProperty", "flag": "IntVectorProperty",
          "choice": "StringVectorProperty"}


def _option_tables(scene=False):
    """(owner, spec) for every option a solve takes: the method's own (owner its name), then the shared
    ones (owner None), then with `scene` those of reading the scene file (owner "scene")."""
    out = []
    for m in radmesh.methods():
        out += [(m["name"], o) for o in m["options"]]
    shared = [(None, o) for o in radmesh.solve_options() + radmesh.meshing_options()]
    if scene:
        shared += [("scene", o) for o in radmesh.scene_options()]
    out += shared
    names = [o["name"] for _, o in out]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:  # one property per name: a second would hide the first
        raise RuntimeError(f"radmesh plugin: options declared twice: {', '.join(twice)}")
    return out


def _label(name):
    return " ".join(w.capitalize() for w in name.split("_"))


def _property_xml(owner, spec):
    """The ServerManager XML of one option: its range or choices, its help, shown only for its method."""
    name, kind = spec["name"], spec["kind"]
    tag = _KINDS[kind]
    default = spec["default"]
    if kind == "flag":
        default = int(default)
    unit = f" ({spec['unit']})" if spec["unit"] else ""
    if kind == "real":
        domain = f'<DoubleRangeDomain name="range" min="{spec["min"]!r}" max="{spec["max"]!r}"/>'
    elif kind == "integer":
        lo, hi = (max(v, -2**31) if i == 0 else min(v, 2**31 - 1) for i, v in enumerate((spec["min"], spec["max"])))
        domain = f'<IntRangeDomain name="range" min="{int(lo)}" max="{int(hi)}"/>'
    elif kind == "flag":
        domain = '<BooleanDomain name="bool"/>'
    else:
        entries = "".join(f'<String value="{c}"/>' for c in spec["choices"])
        domain = f'<StringListDomain name="list">{entries}</StringListDomain>'
    hints = ""
    if owner and owner != "scene":
        hints = ('<Hints><PropertyWidgetDecorator type="GenericDecorator" mode="visibility" property="Method" '
                 f'value="{owner}"/></Hints>')
    help_text = (spec["help"] + unit).replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")
    return (f'<{tag} name="{name}" label="{_label(name)}" command="SetOption_{name}" number_of_elements="1" '
            f'default_values="{default}" panel_visibility="advanced">{domain}'
            f'<Documentation>{help_text}</Documentation>{hints}</{tag}>')


def _method_xml():
    entries = "".join(f'<String value="{m["name"]}"/>' for m in radmesh.methods())
    return (f'<StringVectorProperty name="Method" command="SetMethod" number_of_elements="1" '
            f'default_values="{radmesh.methods()[0]["name"]}"><StringListDomain name="list">{entries}'
            '</StringListDomain><Documentation>The radiosity method.</Documentation></StringVectorProperty>')


def _preset_xml():
    entries = "".join(f'<String value="{name}"/>' for name in ("draft", "default", "fine"))
    return ('<StringVectorProperty name="Preset" command="SetPreset" number_of_elements="1" default_values="default">'
            f'<StringListDomain name="list">{entries}</StringListDomain><Documentation>The method\'s options set '
            'together (radmesh run --preset); an option set here wins over it.</Documentation></StringVectorProperty>')


def _add_options(cls):
    """Gives the class a setter and a property per option (the scene file's too where it reads one), and the
    Method and Preset properties."""
    xmls = [_method_xml(), _preset_xml()]
    for owner, spec in _option_tables(cls._reads_scene):
        def setter(self, value, _spec=spec):
            self._set_option(_spec, value)
        setattr(cls, "SetOption_" + spec["name"], setter)
        xmls.append(_property_xml(owner, spec))
    cls._pvsm_property_xmls = xmls
    return cls


def to_grid(result):
    """An unstructured grid with radiosity.vtu's arrays, from a radmesh.Result."""
    grid = vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(result.points), deep=1))
    grid.SetPoints(points)
    tri = np.asarray(result.triangles, dtype=np.int64)
    cells = vtkCellArray()
    offsets = numpy_support.numpy_to_vtkIdTypeArray(np.arange(0, 3 * len(tri) + 1, 3, dtype=np.int64), deep=1)
    conn = numpy_support.numpy_to_vtkIdTypeArray(tri.reshape(-1).copy(), deep=1)
    cells.SetData(offsets, conn)
    grid.SetCells(VTK_TRIANGLE, cells)

    def add(data, name, values):
        a = numpy_support.numpy_to_vtk(np.ascontiguousarray(values), deep=1)
        a.SetName(name)
        data.AddArray(a)
    add(grid.GetPointData(), "radiosity", result.vertex_radiosity)
    for name, values in result.cell_data().items():
        add(grid.GetCellData(), name, values)
    return grid


class _Solving(VTKPythonAlgorithmBase):
    """What the source and the filter share: the method, its options, the solve."""

    _reads_scene = False

    def __init__(self, inputs, output):
        VTKPythonAlgorithmBase.__init__(self, nInputPorts=inputs, nOutputPorts=1, outputType=output)
        self._method = radmesh.methods()[0]["name"]
        self._preset = "default"
        self._options = {}
        self._owners = {spec["name"]: owner for owner, spec in _option_tables(self._reads_scene)}

    def SetMethod(self, method):
        if method != self._method:
            self._method = method
            self.Modified()

    def SetPreset(self, preset):
        if preset != self._preset:
            self._preset = preset
            self.Modified()

    def _set_option(self, spec, value):
        if spec["kind"] == "flag":
            value = bool(value)
        elif spec["kind"] == "integer":
            value = int(value)
        elif spec["kind"] == "real":
            value = float(value)
        if value == spec["default"]:
            self._options.pop(spec["name"], None)
        else:
            self._options[spec["name"]] = value
        self.Modified()

    def _given(self, owners):
        return {k: v for k, v in self._options.items() if self._owners[k] in owners}

    def _solve(self, scene):
        # Options of another method are left out: their properties are hidden.
        return radmesh.solve(scene, method=self._method, preset=self._preset, **self._given((None, self._method)))


@smproxy.source(name="radmeshScene", label="radmesh Scene")
@smhint.xml('<ShowInMenu category="radmesh"/>')
@_add_options
class RadmeshScene(_Solving):
    """Reads a scene file (OBJ, PLY, STL, OFF, glTF, JSON, MGF) and solves it."""

    _reads_scene = True

    def __init__(self):
        _Solving.__init__(self, 0, "vtkUnstructuredGrid")
        self._file = ""

    @smproperty.stringvector(name="FileName")
    @smdomain.filelist()
    @smhint.filechooser(extensions=["obj", "ply", "stl", "off", "gltf", "glb", "json", "mgf"],
                        file_description="radmesh scenes")
    def SetFileName(self, name):
        if name != self._file:
            self._file = name
            self.Modified()

    def RequestData(self, request, inInfo, outInfo):
        if not self._file:
            raise RuntimeError("radmesh Scene: no file name")
        result = self._solve(radmesh.read_scene(self._file, **self._given(("scene",))))
        vtkUnstructuredGrid.GetData(outInfo).ShallowCopy(to_grid(result))
        return 1


def _rgb_cells(data, name, count, default=None):
    a = data.CellData[name] if name in data.CellData.keys() else None
    if a is None:
        if default is None:
            raise ValueError(f"radmesh Radiosity: the input has no cell array '{name}'")
        return np.tile(default, (count, 1))
    a = np.asarray(a, dtype=float).reshape(count, -1)
    if a.shape[1] == 1:
        a = np.repeat(a, 3, axis=1)
    if a.shape[1] != 3:
        raise ValueError(f"radmesh Radiosity: cell array '{name}' has {a.shape[1]} components; 1 or 3 wanted")
    return a


def scene_of_polydata(poly):
    """A radmesh.Scene from polygons with cell arrays reflectance and emission (see the module's text)."""
    data = dsa.WrapDataObject(poly)
    polys = poly.GetPolys()
    count = polys.GetNumberOfCells()
    if count == 0:
        raise ValueError("radmesh Radiosity: the input has no polygons")
    if poly.GetNumberOfCells() != count:
        raise ValueError(f"radmesh Radiosity: {poly.GetNumberOfCells() - count} cells of the input are not "
                         "polygons (vertices, lines or strips); extract the surface's polygons first")
    offsets = numpy_support.vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    indices = numpy_support.vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    vertices = numpy_support.vtk_to_numpy(poly.GetPoints().GetData()).astype(float)
    rho = _rgb_cells(data, "reflectance", count)
    emission = _rgb_cells(data, "emission", count, default=np.zeros(3))
    pairs, patch_materials = np.unique(np.hstack([rho, emission]), axis=0, return_inverse=True)
    materials = [{"name": f"material_{k}", "reflectance": tuple(p[:3]), "emission": tuple(p[3:])}
                 for k, p in enumerate(pairs)]
    return radmesh.Scene.from_arrays(vertices, (offsets, indices), patch_materials.reshape(-1), materials)


@smproxy.filter(name="radmeshRadiosity", label="radmesh Radiosity")
@smhint.xml('<ShowInMenu category="radmesh"/>')
@smproperty.input(name="Input", port_index=0)
@smdomain.datatype(dataTypes=["vtkPolyData"], composite_data_supported=False)
@_add_options
class RadmeshRadiosity(_Solving):
    """Lights polygonal data whose cell arrays give reflectance and emission."""

    def __init__(self):
        _Solving.__init__(self, 1, "vtkUnstructuredGrid")

    def FillInputPortInformation(self, port, info):
        info.Set(self.INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData")
        return 1

    def RequestData(self, request, inInfo, outInfo):
        result = self._solve(scene_of_polydata(vtkPolyData.GetData(inInfo[0])))
        vtkUnstructuredGrid.GetData(outInfo).ShallowCopy(to_grid(result))
        return 1
