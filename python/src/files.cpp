// radmesh._files: the files of a result (radiosity.vtu, summary.json, the
// pixmap method's state and lightmaps, ...) through the library's writers,
// which use VTK. Apart from _core, so that _core loads where another VTK is
// loaded (ParaView's Python).

#include "io/writers/pixmap_io.h"
#include "python/src/types.h"
#include "radmesh/result_files.h"

#include <pybind11/stl.h>

namespace py = pybind11;
using namespace radmesh;
using namespace radmesh::python;

PYBIND11_MODULE(_files, m) {
  m.doc() = "radmesh's VTK files for radmesh._core's results";
  py::module_ core = py::module_::import("radmesh._core");
  translate_errors(core);
  static PixmapFiles pixmap{&write_pixmap_state, &read_pixmap_state, &write_lightmaps};
  core.attr("_install_pixmap_files")(py::capsule(&pixmap, kPixmapFilesCapsule));
  m.def(
      "write",
      [](const PyResult& r, const std::string& out_dir, bool png) {
        std::vector<std::string> notes, written;
        {
          py::gil_scoped_release release;
          written = write_result_files(out_dir, *r.result, png, &notes);
        }
        return py::make_tuple(written, notes);
      },
      py::arg("result"), py::arg("out_dir"), py::arg("png") = true);
}
