// libFuzzer target: the JSON scene file. The scratch folder holds a small OBJ
// (with its MTL), PLY, STL and OFF that a scene may name (copied from
// fuzz/files/ at start), so mutations reach objects, materials and transforms.

#include "fuzz/fuzz_util.h"
#include "radmesh/scene_reader.h"

#include <filesystem>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  for (const auto& entry : std::filesystem::directory_iterator(RADMESH_FUZZ_FILES))
    std::filesystem::copy_file(entry.path(), radmesh::fuzz::scratch_dir() / entry.path().filename(),
                               std::filesystem::copy_options::overwrite_existing);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  const std::string path = fuzz::write_file("scene.json", {reinterpret_cast<const char*>(data), size});
  try {
    fuzz::check_scene(read_scene(path));
  } catch (const Error&) {
  }
  return 0;
}
