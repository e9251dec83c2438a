// libFuzzer target: an OBJ file and its MTL library (input split at a line
// "#--MTL--", see fuzz_util.h) through read_scene. A typed radmesh error is
// the expected answer to bad input; any other exception, a sanitizer report,
// a hang or a scene that breaks build_scene's promises is a defect.

#include "fuzz/fuzz_util.h"
#include "radmesh/scene_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  const std::string path = fuzz::write_obj_input(data, size);
  try {
    fuzz::check_scene(read_scene(path));
  } catch (const Error&) {
  }
  return 0;
}
