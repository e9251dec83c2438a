// libFuzzer target: the formats radmesh reads through assimp. The first byte
// picks the format (PLY, STL, OFF, glTF, GLB), the rest is the file. glTF
// carries its materials and is read directly; PLY, STL and OFF carry none and
// are read through a JSON scene that gives them one, as users must.

#include "fuzz/fuzz_util.h"
#include "radmesh/scene_reader.h"

#include <array>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  if (size == 0) return 0;
  static constexpr std::array<const char*, 5> kExtensions = {".ply", ".stl", ".off", ".gltf", ".glb"};
  const std::string ext = kExtensions[data[0] % kExtensions.size()];
  const std::string mesh = fuzz::write_file("mesh" + ext, {reinterpret_cast<const char*>(data + 1), size - 1});
  std::string path = mesh;
  if (ext == ".ply" || ext == ".stl" || ext == ".off")
    path = fuzz::write_file("scene.json",
                            R"({"materials": {"grey": {"reflectance": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}},
                                "objects": [{"file": "mesh)" + ext + R"(", "material": "grey"}]})");
  try {
    fuzz::check_scene(read_scene(path));
  } catch (const Error&) {
  }
  return 0;
}
