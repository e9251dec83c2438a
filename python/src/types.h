// The objects the Python module binds, shared by its two extension modules
// (_core makes them, _files writes them: pybind11 finds a type bound in one
// module from the other).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/run.h"
#include "radmesh/scene.h"

#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

namespace radmesh {
struct PixmapOutput;
struct PixmapState;
}  // namespace radmesh

namespace radmesh::python {

namespace py = pybind11;

struct PyScene {
  std::shared_ptr<const Scene> scene;
};

struct PyMesh {
  std::shared_ptr<const Scene> scene;
  std::shared_ptr<const Mesh> mesh;
  MeshingOptions options;
  MeshReport report;
};

struct PyResult {
  std::shared_ptr<const Result> result;
};

// The pixmap method's files are VTK images: _core leaves them to _files,
// which hands it these on import (src/io/writers/pixmap_io.h).
struct PixmapFiles {
  std::vector<std::string> (*write_state)(const std::string& out_dir, const PixmapOutput& out) = nullptr;
  PixmapState (*read_state)(const std::string& dir) = nullptr;
  std::vector<std::string> (*write_lightmaps)(const std::string& out_dir, const Mesh& mesh,
                                              const PixmapOutput& out) = nullptr;
};
inline constexpr const char* kPixmapFilesCapsule = "radmesh._files.PixmapFiles";
// _core's (pixmap_files.cpp): empty until _files hands its functions over.
extern PixmapFiles g_pixmap_files;

// Text from the library as a Python str: bytes that are not UTF-8 (a name
// read from a file in another encoding) become U+FFFD, as in summary.json.
py::str text(const std::string& s);
py::list texts(const std::vector<std::string>& v);

// radmesh's typed errors as the Python exceptions of radmesh._core
// (InputError, GeometryError, NumericalError, IoError, all radmesh.Error):
// each extension module registers this once.
void translate_errors(py::module_ core);

}  // namespace radmesh::python
