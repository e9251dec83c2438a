// radmesh._core: the library for Python, without VTK (so that it loads
// inside ParaView's Python, which brings its own VTK). radmesh/__init__.py
// is the module users import; the VTK files are _files's.

#include "python/src/arrays.h"
#include "python/src/types.h"

#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radmesh/method.h"
#include "radmesh/run.h"
#include "radmesh/scene_reader.h"
#include "radmesh/summary.h"
#include "radmesh/version.h"

#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

namespace py = pybind11;
using namespace radmesh;
using namespace radmesh::python;

namespace {

// ---- errors ---------------------------------------------------------------

// The exception classes, made once here; translate_errors raises them.
void register_errors(py::module_& m) {
  auto make = [&](const char* name, py::object bases, const char* doc) {
    const std::string full = std::string("radmesh.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases.ptr(), nullptr);
    if (!type) throw py::error_already_set();
    m.add_object(name, py::reinterpret_steal<py::object>(type));
    return m.attr(name);
  };
  const py::object error = make("Error", py::reinterpret_borrow<py::object>(PyExc_Exception), "Base of every radmesh error.");
  make("InputError", py::make_tuple(error, py::handle(PyExc_ValueError)),
       "Malformed or out-of-range input: a scene file, an array, an option.");
  make("GeometryError", error, "Geometry that cannot be processed.");
  make("NumericalError", error, "Non-convergence, a non-finite value, a problem too large for memory.");
  make("IoError", py::make_tuple(error, py::handle(PyExc_OSError)), "Reading or writing a file failed.");
  translate_errors(m);
}

// ---- options from keywords ------------------------------------------------

// A keyword value as the option's text, as the radmesh program would get it
// (a float by its shortest exact repr, so the value read back is the same).
std::string option_text(const std::string& name, const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  // As a Python int or float first: a numpy scalar's own repr may name its type.
  if (py::hasattr(value, "__index__")) return py::str(py::int_(py::reinterpret_borrow<py::object>(value)));
  if (py::hasattr(value, "__float__")) return py::repr(py::float_(py::reinterpret_borrow<py::object>(value)));
  throw InputError(name + "=" + py::repr(value).cast<std::string>() + ": not a number, a bool or a string", {name});
}

bool in_specs(const std::vector<OptionSpec>& specs, const std::string& name) {
  for (const OptionSpec& s : specs)
    if (s.name == name) return true;
  return false;
}

struct SortedOptions {
  OptionValues solve, meshing, method;
};

// Keywords sorted into the solve's, the meshing's and the method's options.
SortedOptions sort_options(const Method* method, const py::kwargs& kwargs) {
  SortedOptions out;
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    const std::string text = option_text(name, value);
    if (in_specs(solve_option_table().specs(), name))
      out.solve[name] = text;
    else if (in_specs(meshing_option_table().specs(), name))
      out.meshing[name] = text;
    else if (method)
      out.method[name] = text;  // method_options names the methods that take it, or says none does
    else
      unknown_option(name, "meshing");
  }
  return out;
}

py::dict spec_dict(const OptionSpec& s) {
  static const char* const kinds[] = {"real", "integer", "choice", "flag"};
  py::dict d;
  d["name"] = s.name;
  d["kind"] = kinds[static_cast<int>(s.kind)];
  d["unit"] = s.unit;
  d["help"] = s.help;
  switch (s.kind) {
    case OptionSpec::Kind::choice: d["default"] = s.choices.front(); break;
    case OptionSpec::Kind::flag: d["default"] = s.default_value != 0.0; break;
    case OptionSpec::Kind::integer: d["default"] = static_cast<long long>(s.default_value); break;
    default: d["default"] = s.default_value;
  }
  if (s.kind == OptionSpec::Kind::real || s.kind == OptionSpec::Kind::integer) {
    d["min"] = s.min;
    d["max"] = s.max;
  }
  if (s.kind == OptionSpec::Kind::choice) d["choices"] = s.choices;
  return d;
}

py::list spec_list(const std::vector<OptionSpec>& specs) {
  py::list l;
  for (const OptionSpec& s : specs) l.append(spec_dict(s));
  return l;
}

// ---- the solve, interruptible ---------------------------------------------

// Thrown by the progress callback to stop the library's work (Ctrl-C, or
// the Python callable raised): the solve unwinds and nothing is kept.
struct Stopped {};

// Runs `work` on a thread of its own while this one, holding the GIL now
// and then, passes progress to `progress` (a Python callable, may be None)
// and watches for signals: Ctrl-C stops the work at its next progress
// report and raises KeyboardInterrupt here.
template <class T>
T run_interruptible(const py::object& progress, const std::function<T(const SolveCallbacks&)>& work) {
  std::mutex mu;
  std::condition_variable cv;
  bool done = false, fresh = false;
  std::string phase;
  double fraction = 0.0;
  std::atomic<bool> stop{false};
  std::optional<T> out;
  std::exception_ptr failure;
  SolveCallbacks cb;
  cb.progress = [&](const std::string& ph, double f) {
    if (stop.load()) throw Stopped{};
    std::lock_guard<std::mutex> lock(mu);
    phase = ph;
    fraction = f;
    fresh = true;
  };
  cb.cancelled = [&] { return stop.load(); };
  std::optional<py::error_already_set> raised;
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        out.emplace(work(cb));
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mu);
      done = true;
      cv.notify_all();
    });
    // Whatever leaves this loop, the worker is stopped and joined first.
    struct Joiner {
      std::thread& t;
      std::atomic<bool>& stop;
      ~Joiner() {
        stop = true;
        t.join();
      }
    } joiner{worker, stop};
    using Clock = std::chrono::steady_clock;
    Clock::time_point last = Clock::now() - std::chrono::seconds(1);
    for (;;) {
      std::unique_lock<std::mutex> lock(mu);
      cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; });
      if (done) break;
      // At most ten calls a second, with the last report.
      const bool report = fresh && Clock::now() - last >= std::chrono::milliseconds(100);
      const std::string ph = phase;
      const double f = fraction;
      if (report) fresh = false;
      lock.unlock();
      if (raised) continue;
      py::gil_scoped_acquire acquire;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (report && !progress.is_none()) {
          last = Clock::now();
          progress(ph, f);
        }
      } catch (py::error_already_set& e) {
        raised.emplace(std::move(e));
        stop = true;
      }
    }
  }
  if (raised) throw std::move(*raised);
  if (failure) {
    try {
      std::rethrow_exception(failure);
    } catch (const Stopped&) {
      // Stopped only when asked, and asking raised: kept as a guard.
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
  }
  return std::move(*out);
}

// ---- the bound types --------------------------------------------------------

py::dict material_dict(const Material& mat) {
  py::dict d;
  d["name"] = text(mat.name);
  d["reflectance"] = py::make_tuple(mat.reflectance.x, mat.reflectance.y, mat.reflectance.z);
  d["emission"] = py::make_tuple(mat.emission.x, mat.emission.y, mat.emission.z);
  return d;
}

Rgb rgb_of(const py::handle& value, const std::string& what) {
  if (!py::isinstance<py::sequence>(value) || py::isinstance<py::str>(value))
    throw InputError(what + ": 3 values (r, g, b) wanted, got " + py::repr(value).cast<std::string>());
  const py::sequence s = value.cast<py::sequence>();
  if (s.size() != 3) throw InputError(what + ": 3 values (r, g, b) wanted, got " + std::to_string(s.size()));
  Rgb c;
  for (int k = 0; k < 3; ++k) {
    if (!py::isinstance<py::float_>(s[k]) && !py::isinstance<py::int_>(s[k]) && !py::hasattr(s[k], "__float__"))
      throw InputError(what + "[" + std::to_string(k) + "]: not a number");
    c[k] = s[k].cast<double>();
  }
  return c;
}

std::vector<Material> materials_of(const py::sequence& list) {
  std::vector<Material> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string where_ = "materials[" + std::to_string(k) + "]";
    if (!py::isinstance<py::dict>(list[k]))
      throw InputError(where_ + ": a dict {\"name\": ..., \"reflectance\": (r, g, b), \"emission\": (r, g, b)} wanted");
    const py::dict d = list[k].cast<py::dict>();
    for (const auto& [key, value] : d) {
      const std::string name = py::str(key).cast<std::string>();
      if (name != "name" && name != "reflectance" && name != "emission")
        throw InputError(where_ + ": unknown key '" + name + "' (name, reflectance, emission)");
    }
    if (!d.contains("reflectance")) throw InputError(where_ + ": no reflectance");
    Material m;
    m.name = d.contains("name") ? py::str(d["name"]).cast<std::string>() : "material_" + std::to_string(k);
    m.reflectance = rgb_of(d["reflectance"], where_ + ".reflectance");
    if (d.contains("emission")) m.emission = rgb_of(d["emission"], where_ + ".emission");
    m.file = where_;
    out.push_back(std::move(m));
  }
  return out;
}

PyScene scene_from_arrays(const py::object& vertices, const py::object& faces, const py::object& patch_materials,
                          const py::sequence& materials, const py::object& names) {
  const Matrix v = real_matrix(vertices, "vertices", 3);
  const Polygons polys = polygons(faces, "faces", static_cast<long long>(v.rows));
  const std::vector<long long> mat = integer_vector(patch_materials, "patch_materials");
  if (mat.size() != polys.count())
    throw InputError("patch_materials: " + std::to_string(mat.size()) + " entries for " +
                     std::to_string(polys.count()) + " faces");
  std::vector<Material> mats = materials_of(materials);
  std::vector<std::string> face_names;
  if (!names.is_none()) {
    try {
      face_names = names.cast<std::vector<std::string>>();
    } catch (const py::cast_error&) {
      throw InputError("names: a list of strings wanted, one per face");
    }
    if (face_names.size() != polys.count())
      throw InputError("names: " + std::to_string(face_names.size()) + " for " + std::to_string(polys.count()) +
                       " faces");
  }
  std::vector<RawFace> raw(polys.count());
  for (size_t f = 0; f < raw.size(); ++f) {
    RawFace& face = raw[f];
    const std::string at = "faces[" + std::to_string(f) + "]";
    if (mat[f] < 0 || mat[f] >= static_cast<long long>(mats.size()))
      throw InputError("patch_materials[" + std::to_string(f) + "]: " + std::to_string(mat[f]) +
                       " is not a material index (" + std::to_string(mats.size()) + " materials)");
    face.material = static_cast<int>(mat[f]);
    face.name = face_names.empty() ? "face_" + std::to_string(f) : face_names[f];
    face.file = at;
    for (long long i = polys.offsets[f]; i < polys.offsets[f + 1]; ++i) face.points.push_back(v.row(polys.indices[i]));
  }
  PyScene s;
  s.scene = std::make_shared<const Scene>(build_scene(raw, std::move(mats), "arrays"));
  return s;
}

PyMesh mesh_of(const PyScene& s, const py::kwargs& kwargs) {
  const SortedOptions o = sort_options(nullptr, kwargs);
  if (!o.solve.empty()) unknown_option(o.solve.begin()->first, "meshing");
  PyMesh m;
  m.scene = s.scene;
  m.options = resolve_meshing_options(*s.scene, meshing_option_table().parse(o.meshing));
  {
    py::gil_scoped_release release;
    m.mesh = std::make_shared<const Mesh>(mesh_scene(*s.scene, m.options, &m.report));
  }
  return m;
}

PyResult solve_scene(const PyScene& s, const std::string& method_name, const py::object& progress,
                     const py::object& resume, const std::string& preset, const py::kwargs& kwargs) {
  const Method& method = find_method(method_name);
  SortedOptions o = sort_options(&method, kwargs);
  apply_preset(method, preset, o.solve, o.meshing, o.method);
  const MethodOptions mo = method_options(method, o.method);
  const SolveOptions common = solve_option_table().parse(o.solve);
  std::shared_ptr<const MethodState> state;
  if (!resume.is_none()) state = read_method_state(method, py::str(resume).cast<std::string>());
  PyResult r;
  r.result = run_interruptible<std::shared_ptr<const Result>>(progress, [&](const SolveCallbacks& cb) {
    SolveCallbacks with = cb;
    with.resume = state;
    auto solved = std::make_shared<Result>(solve(*s.scene, method, mo, common, with, o.meshing));
    solved->preset = preset;
    std::shared_ptr<const Result> out = std::move(solved);
    if (out->interrupted) throw Stopped{};  // a method that stops on its own when asked (cb.cancelled)
    return out;
  });
  return r;
}

py::dict quality_of(const Mesh& mesh, int patches,
                    const std::vector<DiscontinuitySegment>& lines) {
  auto q = std::make_shared<TriangleQuality>(compute_quality(mesh));
  std::shared_ptr<const void> keep = q;
  py::dict d;
  d["min_angle"] = view(q->min_angle, keep);
  d["max_angle"] = view(q->max_angle, keep);
  d["aspect_ratio"] = view(q->aspect_ratio, keep);
  d["zero_area"] = view_bool(q->zero_area, keep);
  py::list rows;
  for (const PatchQuality& r : patch_quality(patches, mesh, *q, lines)) {
    py::dict row;
    row["patch"] = r.patch;
    row["triangles"] = r.triangles;
    row["min_angle"] = r.min_angle;
    row["max_angle"] = r.max_angle;
    row["aspect_p50"] = r.aspect_p50;
    row["aspect_p95"] = r.aspect_p95;
    row["aspect_max"] = r.aspect_max;
    row["contact_segments"] = r.contact_segments;
    row["d1_segments"] = r.d1_segments;
    row["d2_segments"] = r.d2_segments;
    row["zero_area"] = r.zero_area;
    rows.append(row);
  }
  d["patches"] = rows;
  return d;
}

py::array zero_area_flags(const Mesh& mesh) {
  auto flags = std::make_shared<std::vector<char>>(mesh.triangles.size());
  for (size_t t = 0; t < flags->size(); ++t) (*flags)[t] = mesh.zero_area(static_cast<int>(t)) ? 1 : 0;
  return view_bool(*flags, flags);
}

// The cell arrays of radiosity.vtu, in its order (src/io/writers/vtk_writer.cpp):
// the elements' radiosity, patch_id, area, min_angle, aspect_ratio, the
// patch material's reflectance and emission, then the method's own fields.
py::dict cell_data(const std::shared_ptr<const Result>& r) {
  const Mesh& mesh = r->mesh;
  const Scene& scene = *r->scene;
  auto q = std::make_shared<TriangleQuality>(compute_quality(mesh));
  auto per_cell = std::make_shared<std::array<std::vector<Vec3>, 2>>();  // reflectance, emission
  auto area = std::make_shared<std::vector<double>>(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Material& mat = scene.material_of(scene.patches[static_cast<size_t>(mesh.patch[t])]);
    (*per_cell)[0].push_back(mat.reflectance);
    (*per_cell)[1].push_back(mat.emission);
    (*area)[t] = mesh.area(static_cast<int>(t));
  }
  py::dict d;
  d["radiosity"] = view_rows(r->solution.element, r);
  d["patch_id"] = view(mesh.patch, r);
  d["area"] = view(*area, area);
  d["min_angle"] = view(q->min_angle, q);
  d["aspect_ratio"] = view(q->aspect_ratio, q);
  d["reflectance"] = view_rows((*per_cell)[0], per_cell);
  d["emission"] = view_rows((*per_cell)[1], per_cell);
  for (const auto& [name, values] : r->cell_fields) d[py::str(name)] = view(values, r);
  return d;
}

py::array means_array(const std::vector<Rgb>& means) {
  auto copy = std::make_shared<std::vector<Rgb>>(means);
  return view_rows(*copy, copy);
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "radmesh's library without its VTK files (see radmesh/__init__.py)";
  m.attr("__version__") = RADMESH_VERSION;
  register_errors(m);

  py::class_<PyScene>(m, "Scene", "A validated scene: welded vertices, planar patches, materials.")
      .def_static("from_arrays", &scene_from_arrays, py::arg("vertices"), py::arg("faces"),
                  py::arg("patch_materials"), py::arg("materials"), py::arg("names") = py::none())
      .def_property_readonly("source", [](const PyScene& s) { return text(s.scene->source); })
      .def_property_readonly("vertices", [](const PyScene& s) { return view_rows(s.scene->vertices, s.scene); })
      .def_property_readonly("patch_count", [](const PyScene& s) { return s.scene->patches.size(); })
      .def_property_readonly("patch_names",
                             [](const PyScene& s) {
                               py::list n;
                               for (const Patch& p : s.scene->patches) n.append(text(p.name));
                               return n;
                             })
      .def_property_readonly("patch_materials",
                             [](const PyScene& s) {
                               auto mats = std::make_shared<std::vector<int>>();
                               for (const Patch& p : s.scene->patches) mats->push_back(p.material);
                               return view(*mats, mats);
                             })
      .def_property_readonly("patches",
                             [](const PyScene& s) {
                               // (offsets, indices) of the outer loops; holes are not listed.
                               auto offsets = std::make_shared<std::vector<long long>>(1, 0);
                               auto indices = std::make_shared<std::vector<long long>>();
                               for (const Patch& p : s.scene->patches) {
                                 for (int v : p.outer) indices->push_back(v);
                                 offsets->push_back(static_cast<long long>(indices->size()));
                               }
                               return py::make_tuple(view(*offsets, offsets), view(*indices, indices));
                             })
      .def_property_readonly("materials",
                             [](const PyScene& s) {
                               py::list l;
                               for (const Material& mat : s.scene->materials) l.append(material_dict(mat));
                               return l;
                             })
      .def_property_readonly("warnings", [](const PyScene& s) { return texts(s.scene->report.warnings); })
      .def("__repr__", [](const PyScene& s) {
        return text("<radmesh.Scene " + s.scene->source + ": " + std::to_string(s.scene->patches.size()) + " patches>");
      });

  py::class_<PyMesh>(m, "Mesh", "A scene's all-triangle mesh.")
      .def_property_readonly("points", [](const PyMesh& me) { return view_rows(me.mesh->positions, me.mesh); })
      .def_property_readonly("triangles", [](const PyMesh& me) { return view_rows(me.mesh->triangles, me.mesh); })
      .def_property_readonly("patch", [](const PyMesh& me) { return view(me.mesh->patch, me.mesh); })
      .def_property_readonly("zero_area", [](const PyMesh& me) { return zero_area_flags(*me.mesh); })
      .def_property_readonly("warnings", [](const PyMesh& me) { return texts(me.report.warnings); })
      .def_property_readonly("max_edge", [](const PyMesh& me) { return me.options.max_edge; })
      .def_property_readonly("contact_segments", [](const PyMesh& me) { return me.report.contact_segments; })
      .def_property_readonly("shadow_segments", [](const PyMesh& me) { return me.report.shadow_segments; })
      .def("__repr__", [](const PyMesh& me) {
        return "<radmesh.Mesh " + std::to_string(me.mesh->triangles.size()) + " triangles>";
      });

  py::class_<PyResult>(m, "Result", "A solved scene: the field users see on its mesh, and the run's figures.")
      .def_property_readonly("method", [](const PyResult& r) { return r.result->method; })
      .def_property_readonly("points", [](const PyResult& r) { return view_rows(r.result->solution.nodal.points, r.result); })
      .def_property_readonly("triangles",
                             [](const PyResult& r) { return view_rows(r.result->solution.nodal.corners, r.result); })
      .def_property_readonly("patch", [](const PyResult& r) { return view(r.result->mesh.patch, r.result); })
      .def_property_readonly("zero_area", [](const PyResult& r) { return zero_area_flags(r.result->mesh); })
      .def_property_readonly("vertex_radiosity",
                             [](const PyResult& r) { return view_rows(r.result->solution.nodal.radiosity, r.result); })
      .def_property_readonly("triangle_radiosity",
                             [](const PyResult& r) { return view_rows(r.result->solution.element, r.result); })
      .def("cell_data", [](const PyResult& r) { return cell_data(r.result); })
      .def("patch_means", [](const PyResult& r) { return means_array(r.result->patch_means()); })
      .def("element_patch_means", [](const PyResult& r) { return means_array(r.result->element_patch_means()); })
      .def("summary_text", [](const PyResult& r) { return summary_text(*r.result); })
      .def_property_readonly("warnings", [](const PyResult& r) { return texts(r.result->warnings); })
      .def("__repr__", [](const PyResult& r) {
        return "<radmesh.Result " + r.result->method + ": " + std::to_string(r.result->mesh.triangles.size()) +
               " triangles>";
      });

  m.def("read_scene", [](const std::string& path, const py::kwargs& kwargs) {
    OptionValues given;
    for (const auto& [key, value] : kwargs) {
      const std::string name = key.cast<std::string>();
      given[name] = option_text(name, value);
    }
    const SceneOptions options = scene_option_table().parse(given);
    PyScene s;
    py::gil_scoped_release release;
    s.scene = std::make_shared<const Scene>(read_scene(path, options));
    return s;
  }, py::arg("path"));
  m.def("mesh", &mesh_of, py::arg("scene"));
  m.def("solve", &solve_scene, py::arg("scene"), py::arg("method") = methods().front().name,
        py::arg("progress") = py::none(), py::arg("resume") = py::none(), py::arg("preset") = "default");
  m.def("quality", [](const PyMesh& me) {
    return quality_of(*me.mesh, static_cast<int>(me.scene->patches.size()), me.report.discontinuities);
  }, py::arg("mesh"));
  m.def("methods", [] {
    py::list l;
    for (const Method& method : methods()) {
      py::dict d;
      d["name"] = method.name;
      d["help"] = method.help;
      d["options"] = spec_list(method.options);
      d["unused"] = method.unused;
      d["resumable"] = method.resumable();
      py::dict presets;
      for (const Preset& p : method.presets) presets[py::str(p.name)] = p.values;
      d["presets"] = presets;
      l.append(d);
    }
    return l;
  });
  m.def("_install_pixmap_files", [](const py::capsule& c) {
    if (c.name() == nullptr || std::string(c.name()) != kPixmapFilesCapsule)
      throw InputError("_install_pixmap_files: not radmesh._files's capsule");
    g_pixmap_files = *c.get_pointer<PixmapFiles>();
  });
  m.def("solve_options", [] { return spec_list(solve_option_table().specs()); });
  m.def("meshing_options", [] { return spec_list(meshing_option_table().specs()); });
  m.def("scene_options", [] { return spec_list(scene_option_table().specs()); });
}
