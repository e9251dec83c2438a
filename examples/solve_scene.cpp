// Reads a scene, solves it with hierarchical radiosity, writes the result
// for ParaView with its summary, and prints every patch's mean radiosity.
//   solve_scene SCENE OUT_DIR
#include <radmesh/radmesh.h>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SCENE OUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const radmesh::Scene scene = radmesh::read_scene(argv[1]);
    radmesh::HierarchicalOptions options;
    options.epsilon = 0.01;
    const radmesh::Result result = radmesh::solve(scene, options);
    const std::filesystem::path out = argv[2];
    std::filesystem::create_directories(out);
    radmesh::write_vtu((out / "radiosity.vtu").string(), result);
    radmesh::write_summary((out / "summary.json").string(), result);
    const std::vector<radmesh::Rgb> means = result.patch_means();
    for (size_t p = 0; p < scene.patches.size(); ++p)
      std::printf("%-20s %.6g %.6g %.6g\n", scene.patches[p].name.c_str(), means[p].x, means[p].y, means[p].z);
    return 0;
  } catch (const radmesh::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
