// libFuzzer target: an MGF file through the MGF reader, then build_scene.
// The input is one file: an include names a file that is not there (an
// error) or the input itself (a cycle). The reader runs with bounds on the
// work its arrays and curved primitives may ask for that keep one input
// within the fuzzer's time (the defaults are for real scenes). A typed
// radmesh error is the expected answer to bad input; any other exception, a
// sanitizer report, a hang or a scene that breaks build_scene's promises is
// a defect.

#include "fuzz/fuzz_util.h"
#include "io/readers/scene_sources.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  const std::string path =
      fuzz::write_file("scene.mgf", std::string_view(reinterpret_cast<const char*>(data), size));
  internal::MgfLimits limits;
  limits.faces = 20000;
  limits.statements = 1000000;
  try {
    const internal::SceneSource source = internal::read_mgf_source(path, {}, limits);
    fuzz::check_scene(build_scene(source.faces, source.materials, path));
  } catch (const Error&) {
  }
  return 0;
}
