// Shared by the libFuzzer targets: a scratch folder per process for the files
// an input becomes, the rule for which exceptions are expected, and checks of
// what a successful read or meshing must satisfy.
#pragma once

#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radmesh/scene.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <unistd.h>
#include <vector>

namespace radmesh::fuzz {

// A folder of this process's own, made once, removed at exit. The path is
// never destroyed: a static path object would be destroyed before the exit
// handler registered during its construction ran, and the handler would
// then read a dead path and remove nothing, leaving the folder behind.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path* const dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    auto* d = new std::filesystem::path(std::filesystem::path(tmp && *tmp ? tmp : "/tmp") /
                                        ("radmesh-fuzz-" + std::to_string(::getpid())));
    std::filesystem::create_directories(*d);
    std::atexit([] { std::error_code ec; std::filesystem::remove_all(*dir, ec); });
    return d;
  }();
  return *dir;
}

inline std::string write_file(const std::string& name, std::string_view bytes) {
  const std::filesystem::path p = scratch_dir() / name;
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p.string();
}

// Splits the input at the first line "#--MTL--": the part before is the OBJ,
// the part after its material library (written as scene.mtl, which the OBJ
// names with `mtllib scene.mtl`).
inline std::pair<std::string_view, std::string_view> split_obj_mtl(const uint8_t* data, size_t size) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view marker = "\n#--MTL--\n";
  const size_t at = all.find(marker);
  if (at == std::string_view::npos) return {all, {}};
  return {all.substr(0, at + 1), all.substr(at + marker.size())};
}

// Writes the input as scene.obj and scene.mtl (see split_obj_mtl); returns
// the OBJ's path.
inline std::string write_obj_input(const uint8_t* data, size_t size) {
  const auto [obj, mtl] = split_obj_mtl(data, size);
  write_file("scene.mtl", mtl);
  return write_file("scene.obj", obj);
}

// A defect found: says what and aborts, which libFuzzer reports with the input.
[[noreturn]] inline void defect(const std::string& what) {
  std::fprintf(stderr, "radmesh fuzz: %s\n", what.c_str());
  std::abort();
}

inline bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// What a scene that read without error must be: finite coordinates, values in
// the ranges build_scene promises, patches of positive finite area.
inline void check_scene(const Scene& scene) {
  for (const Vec3& v : scene.vertices)
    if (!finite(v)) defect("scene vertex not finite");
  for (const Material& m : scene.materials) {
    for (int c = 0; c < 3; ++c) {
      if (!(m.reflectance[c] >= 0.0 && m.reflectance[c] < 1.0)) defect("reflectance out of [0, 1)");
      if (!(m.emission[c] >= 0.0 && std::isfinite(m.emission[c]))) defect("emission negative or not finite");
    }
  }
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const double a = scene.patch_area(static_cast<int>(p));
    if (!(a > 0.0 && std::isfinite(a))) defect("patch " + std::to_string(p) + " area not positive and finite");
  }
}

// What a mesh must be: indices in range, finite positions, and per patch the
// triangles' total area equal to the patch's area (nothing lost or doubled).
inline void check_mesh(const Scene& scene, const Mesh& mesh) {
  const int nv = static_cast<int>(mesh.positions.size());
  for (const Vec3& v : mesh.positions)
    if (!finite(v)) defect("mesh position not finite");
  if (mesh.patch.size() != mesh.triangles.size()) defect("mesh patch array size");
  std::vector<double> area(scene.patches.size(), 0.0);
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    for (const int i : mesh.triangles[static_cast<size_t>(t)])
      if (i < 0 || i >= nv) defect("mesh vertex index out of range");
    const int p = mesh.patch[static_cast<size_t>(t)];
    if (p < 0 || p >= static_cast<int>(scene.patches.size())) defect("mesh patch index out of range");
    area[static_cast<size_t>(p)] += mesh.area(t);
  }
  // Up to rounding, and up to the perimeter times how far a boundary point
  // may lie off where the patch's area puts it: points within the weld
  // tolerance moved onto the patch's edges (the vertex of a face standing
  // 1e-10 from a thin strip's edge joins that edge), and a planar face's
  // vertices up to the planarity tolerance x its diameter off its plane
  // (a point it shares with a face at an angle lands that far inside or
  // outside its outline: 1.6e-6 of a unit face 5e-6 out of plane).
  const SceneOptions tolerances;
  const double weld = tolerances.weld_tolerance * scene.diagonal();
  for (size_t p = 0; p < area.size(); ++p) {
    const double want = scene.patch_area(static_cast<int>(p));
    const Patch& patch = scene.patches[p];
    const std::vector<Vec3> outer = scene.loop_points(patch.outer);
    double perimeter = loop_length(outer);
    for (const auto& h : patch.holes) perimeter += loop_length(scene.loop_points(h));
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const Vec3& q : outer) {
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
    const double off_plane = tolerances.planarity_tolerance * glm::length(hi - lo);
    if (std::abs(area[p] - want) > 1e-6 * want + (weld + off_plane) * perimeter)
      defect("patch " + std::to_string(p) + ": mesh area " + std::to_string(area[p]) + " != patch area " +
             std::to_string(want));
  }
}

}  // namespace radmesh::fuzz
