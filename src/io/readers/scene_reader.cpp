// read_scene: one entry point for every scene format, dispatching on the extension.

#include "radmesh/scene_reader.h"

#include "radmesh/obj_reader.h"
#include "io/readers/scene_sources.h"
#include "radmesh/errors.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace radmesh {

namespace internal {

void check_input_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw IoError(path + ": no such file");
  if (fs::is_directory(st)) throw IoError(path + ": is a directory, not " + what);
  if (!fs::is_regular_file(st))
    throw IoError(path + ": not a regular file (a device, pipe or socket), not " + what +
                  "; radmesh reads regular files only");
  const auto size = fs::file_size(path, ec);
  if (!ec && static_cast<double>(size) > kMaxInputBytes)
    throw IoError(path + ": " + std::to_string(size) + " bytes, more than the " +
                  std::to_string(static_cast<long long>(kMaxInputBytes)) + " radmesh reads as " + what);
}

}  // namespace internal


namespace internal {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool is_assimp_extension(const std::string& ext) {
  return ext == ".ply" || ext == ".stl" || ext == ".off" || ext == ".gltf" || ext == ".glb";
}

}  // namespace internal

namespace {

const char* const kAccepted = ".obj, .ply, .stl, .off, .gltf, .glb, .mgf and .json (a JSON scene)";

// Builds the scene from one file's faces, passing build_scene only the
// materials some face uses (so that an unused one cannot fail the check).
Scene build_from_source(internal::SceneSource source, const std::string& path, const SceneOptions& options) {
  std::vector<int> remap(source.materials.size(), -1);
  std::vector<Material> used;
  for (RawFace& f : source.faces) {
    int& r = remap[static_cast<size_t>(f.material)];
    if (r < 0) {
      r = static_cast<int>(used.size());
      used.push_back(source.materials[static_cast<size_t>(f.material)]);
    }
    f.material = r;
  }
  Scene scene = build_scene(source.faces, std::move(used), path, options);
  std::vector<std::string> warnings = std::move(source.geometry_warnings);
  warnings.insert(warnings.end(), source.warnings.begin(), source.warnings.end());
  scene.report.warnings.insert(scene.report.warnings.begin(), warnings.begin(), warnings.end());
  return scene;
}

}  // namespace

Scene read_scene(const std::string& path, const SceneOptions& options) {
  const std::string ext = internal::lower_extension(path);
  if (ext == ".obj") return read_obj_scene(path, options);
  if (ext == ".json") return internal::read_json_scene(path, options);
  if (ext == ".mgf") return build_from_source(internal::read_mgf_source(path, options), path, options);
  if (internal::is_assimp_extension(ext)) {
    internal::SceneSource source = internal::read_assimp_source(path, /*check_materials=*/true);
    if (!source.missing_material.empty()) {
      const std::string file = std::filesystem::path(path).filename().string();
      throw InputError(path + ": " + source.missing_material +
                       ", and every face needs a reflectance: put the mesh in a JSON scene that gives it a "
                       "material, e.g. {\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5]}}, "
                       "\"objects\": [{\"file\": \"" + file + "\", \"material\": \"grey\"}]}");
    }
    return build_from_source(std::move(source), path, options);
  }
  throw InputError(path + ": " + (ext.empty() ? std::string("no file extension") : "unknown extension '" + ext + "'") +
                   "; radmesh reads " + kAccepted);
}

}  // namespace radmesh
