// Internal to radmesh_io (not installed, not for users): the faces and materials
// one scene file carries, before build_scene, so that a JSON scene can combine
// several files into one face list. The public entry point is radmesh/scene_reader.h.
#pragma once

#include "radmesh/scene.h"

#include <algorithm>
#include <string>
#include <vector>

namespace radmesh::internal {

struct SceneSource {
  // Material indexes `materials`, or -1 where the file gives the face none.
  std::vector<RawFace> faces;
  std::vector<Material> materials;
  // Why some face has no material (e.g. "PLY files carry no materials"); empty
  // when every face has one.
  std::string missing_material;
  // About the file's materials (textures read but not used, MGF's colour
  // conversions, ...): dropped where a JSON scene gives the object a
  // material of its own.
  std::vector<std::string> warnings;
  // About the faces themselves (MGF's curves cut, entities ignored): kept
  // whatever material the faces are given.
  std::vector<std::string> geometry_warnings;
};

// A face's points moved by `apply` (a point map, the JSON scene's or MGF's
// transform); a map that mirrors reverses each loop (keeping its first
// vertex), so that the face keeps facing the same side of its surface.
template <class Apply>
void transform_face(RawFace& f, Apply&& apply, bool mirrors) {
  for (Vec3& p : f.points) p = apply(p);
  for (auto& h : f.holes)
    for (Vec3& p : h) p = apply(p);
  if (mirrors) {
    std::reverse(f.points.begin() + 1, f.points.end());
    for (auto& h : f.holes) std::reverse(h.begin() + 1, h.end());
  }
}

// OBJ + MTL (tinyobjloader, with our own line-numbered checks).
SceneSource read_obj_source(const std::string& path);

// PLY, STL, OFF, glTF 2.0 (.gltf, .glb) through assimp. With check_materials,
// every material a face uses is checked here (messages name the format's keys);
// without, the caller replaces them.
SceneSource read_assimp_source(const std::string& path, bool check_materials);

// MGF 2.0 (mgf_reader.cpp; docs/scenes.md, "MGF"): its includes read
// relative to it, its curved primitives cut into planar faces within
// options.curve_tolerance. The bounds on the work an MGF file may ask for
// (arrays and includes repeat statements); a file past one is refused,
// naming it.
struct MgfLimits {
  long long faces = 10'000'000;        // faces made: f, fh, prisms, the faces of curved primitives
  long long statements = 100'000'000;  // statements executed, each array instance and include counted
  int include_depth = 32;              // includes nested in includes
  // Vertices of one face statement: splitting a face at its seams rescans
  // it after each cut, so a face's work grows as its vertices squared.
  long long face_vertices = 10'000;
  long long points = 100'000'000;      // face vertices made in all (memory: 24 bytes each)
  int object_depth = 64;               // o groups nested (a face's name joins them all)
};
SceneSource read_mgf_source(const std::string& path, const SceneOptions& options, const MgfLimits& limits = {});

// The JSON scene file (radmesh/scene_reader.h describes its keys).
Scene read_json_scene(const std::string& path, const SceneOptions& options);

// Checks that `path` names a regular file radmesh can read (IoError
// otherwise: missing, a directory, a device or pipe such as /dev/zero that
// would be read forever, or larger than kMaxInputBytes). `what` names the
// file's role in the message ("OBJ file", "material library", ...).
inline constexpr double kMaxInputBytes = 8.0 * 1024 * 1024 * 1024;
void check_input_file(const std::string& path, const std::string& what);

// The file name's extension, lower case, with its dot (".ply"); "" when none.
std::string lower_extension(const std::string& path);

// Whether `ext` (as lower_extension returns it) is read through assimp.
bool is_assimp_extension(const std::string& ext);

}  // namespace radmesh::internal
