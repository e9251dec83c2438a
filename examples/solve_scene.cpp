// Reads a scene, meshes it, solves it with the default method, writes the
// result for ParaView and prints every patch's mean radiosity.
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
    const radmesh::Method& method = radmesh::methods().front();  // the default: hierarchical
    const radmesh::Mesh mesh = radmesh::mesh_scene(scene, method.meshing(scene));
    radmesh::SolveOptions options;
    const radmesh::MethodResult result =
        radmesh::run_method(method, scene, mesh, options, {{"epsilon", "0.01"}});
    std::filesystem::create_directories(argv[2]);
    radmesh::write_vtu(std::string(argv[2]) + "/radiosity.vtu", scene, result.mesh,
                       radmesh::compute_quality(result.mesh), result.solution, result.cell_fields);
    const auto means = radmesh::patch_mean_radiosity(scene, result.mesh, result.solution.nodal);
    for (size_t p = 0; p < scene.patches.size(); ++p)
      std::printf("%-20s %.6g %.6g %.6g\n", scene.patches[p].name.c_str(), means[p].x, means[p].y, means[p].z);
    return 0;
  } catch (const radmesh::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
