// libFuzzer target: a scene read as fuzz_obj_reader reads it, then meshed
// (default edge length, discontinuity lines on, as `radmesh mesh` does), with
// the mesh checked: indices in range, finite positions, and each patch's
// triangles covering exactly its area.

#include "fuzz/fuzz_util.h"
#include "radmesh/scene_reader.h"
#include "radmesh/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  const std::string path = fuzz::write_obj_input(data, size);
  try {
    const Scene scene = read_scene(path);
    MeshingOptions options;
    // Keeps one input's meshing to a fraction of a second; larger meshes
    // are refused with an InputError, which is itself under test here.
    options.max_elements = 2e4;
    options = resolve_meshing_options(scene, options);
    fuzz::check_mesh(scene, mesh_scene(scene, options));
  } catch (const Error&) {
  }
  return 0;
}
