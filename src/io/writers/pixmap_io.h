// The pixmap method's files: its state (one VTK image per pixmap and a JSON
// index, enough to resume bit for bit) and its lightmaps (tone-mapped PNGs
// and an OBJ + MTL that shows them on the geometry in any 3-D viewer).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/pixmap.h"

#include <memory>
#include <string>
#include <vector>

namespace radmesh {

// What a pixmap run leaves for the files: the solver (its grids and its
// copy of the scene), the state to save, and the texel values shown (with
// the ambient term).
struct PixmapOutput {
  std::shared_ptr<const PixmapSolver> solver;
  PixmapState state;
  Rgb ambient{0.0};
  std::vector<std::vector<float>> display;  // per pixmap, RGB per texel
};

// OUT/pixmaps/pixmap_K.vti (float RGB cell arrays "radiosity", "unshot",
// and "coverage", the covered fraction, on the texel grid placed in its
// plane) and OUT/pixmaps/state.json (shots, powers, options, the scene's
// fingerprint, and which file is which patches). Files of an earlier run
// there that this one does not write again are removed. Returns the paths
// written; IoError naming the file when one cannot be written.
std::vector<std::string> write_pixmap_state(const std::string& out_dir, const PixmapOutput& out);

// Reads DIR/pixmaps/state.json and its images. IoError when a file cannot
// be read, InputError naming the file and the key or array when one is
// missing or wrong. Whether the state fits a scene and options is
// check_resumable's to say.
PixmapState read_pixmap_state(const std::string& dir);

// OUT/lightmaps/pixmap_K.png (the displayed radiosity, one exposure for
// all, sRGB; uncovered texels take their covered neighbours' values so that
// texture filtering does not darken borders) and OUT/lightmapped.obj + .mtl
// (the display mesh `mesh` with each vertex's texel coordinates as `vt`,
// one material per pixmap with map_Kd). Returns the paths written.
std::vector<std::string> write_lightmaps(const std::string& out_dir, const Mesh& mesh, const PixmapOutput& out);

}  // namespace radmesh
