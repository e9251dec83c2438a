// _core's pixmap files: what src/io/writers/pixmap_io.cpp does with VTK, done
// by the functions _files hands over on import (types.h, PixmapFiles).

#include "io/writers/pixmap_io.h"
#include "python/src/types.h"
#include "radmesh/errors.h"

namespace radmesh::python {

PixmapFiles g_pixmap_files;

namespace {

const PixmapFiles& files() {
  if (!g_pixmap_files.write_state)
    throw IoError("the pixmap method's state and lightmaps are VTK files: import radmesh._files (Result.write "
                  "and radmesh.solve(..., resume=...) do) to read or write them");
  return g_pixmap_files;
}

}  // namespace

}  // namespace radmesh::python

namespace radmesh {

std::vector<std::string> write_pixmap_state(const std::string& out_dir, const PixmapOutput& out) {
  return python::files().write_state(out_dir, out);
}

PixmapState read_pixmap_state(const std::string& dir) { return python::files().read_state(dir); }

std::vector<std::string> write_lightmaps(const std::string& out_dir, const Mesh& mesh, const PixmapOutput& out) {
  return python::files().write_lightmaps(out_dir, mesh, out);
}

}  // namespace radmesh
