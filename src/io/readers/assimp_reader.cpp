// PLY, STL, OFF and glTF 2.0 through assimp: the only file that sees an assimp type.
//
// assimp gives geometry only. No post-processing step runs that would change
// it (no triangulation, welding, normal generation or splitting): faces come
// out in file order with their own vertex order, so that the same mesh in any
// format gives the same face list. We apply node transforms ourselves, in
// double, and reverse the faces of a mirroring node. assimp stores positions
// as float (Debian builds it without ASSIMP_DOUBLE_PRECISION): coordinates are
// rounded to float, about 7 significant digits. glTF materials are read from
// the glTF JSON itself (assimp 5.2 drops KHR_materials_emissive_strength and
// rounds factors to float).

#include "io/readers/gltf_check.h"
#include "io/readers/json_parse.h"
#include "io/readers/mesh_checks.h"
#include "io/readers/scene_sources.h"
#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <regex>
#include <vector>

namespace radmesh::internal {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// assimp logs some defects as errors and goes on (an OFF face's vertex index
// out of range becomes the last vertex): we collect its error messages during
// one import and refuse the file when there are any. The logger is global in
// assimp, so imports are serialised.
std::mutex& import_mutex() {
  static std::mutex m;
  return m;
}

class ErrorCollector : public Assimp::LogStream {
public:
  void write(const char* message) override {
    std::string m = message;
    while (!m.empty() && (m.back() == '\n' || m.back() == '\r')) m.pop_back();
    // "Error, T0: text" -> "text" (and "Warn,  T0: text")
    const size_t colon = m.find(": ");
    if ((m.rfind("Error", 0) == 0 || m.rfind("Warn", 0) == 0) && colon != std::string::npos) m = m.substr(colon + 2);
    messages.push_back(m);
  }
  std::vector<std::string> messages;
};

class ErrorCapture {
public:
  ErrorCapture() {
    created_ = Assimp::DefaultLogger::isNullLogger();
    if (created_) Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);
    Assimp::DefaultLogger::get()->attachStream(&stream_, Assimp::Logger::Err);
    Assimp::DefaultLogger::get()->attachStream(&warnings_, Assimp::Logger::Warn);
  }
  ~ErrorCapture() {
    Assimp::DefaultLogger::get()->detachStream(&warnings_, Assimp::Logger::Warn);
    Assimp::DefaultLogger::get()->detachStream(&stream_, Assimp::Logger::Err);
    if (created_) Assimp::DefaultLogger::kill();
  }
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;
  const std::vector<std::string>& messages() const { return stream_.messages; }
  // The first warning that says assimp dropped or defaulted geometry (a
  // face with an index out of range, the vertices short of a triangle, a
  // value it could not parse); "" when none. radmesh's own checks refuse
  // such files first: this is the second line.
  std::string dropped() const {
    static const char* const kDropped[] = {"dropped", "Unable to parse", "not yet complete", "unexpected EOF"};
    for (const std::string& m : warnings_.messages)
      for (const char* d : kDropped)
        if (m.find(d) != std::string::npos) return m;
    return "";
  }

private:
  bool created_ = false;
  ErrorCollector stream_;
  ErrorCollector warnings_;
};

// An affine map in double: rows of [linear | translation].
struct Affine {
  std::array<std::array<double, 4>, 3> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
  bool identity = true;

  static Affine from(const aiMatrix4x4& a) {
    Affine t;
    const float r[3][4] = {{a.a1, a.a2, a.a3, a.a4}, {a.b1, a.b2, a.b3, a.b4}, {a.c1, a.c2, a.c3, a.c4}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) t.m[i][j] = r[i][j];
    for (int i = 0; i < 3; ++i)  // exactly (assimp's IsIdentity() allows 1e-2)
      for (int j = 0; j < 4; ++j) t.identity = t.identity && r[i][j] == (i == j ? 1.0f : 0.0f);
    return t;
  }
  Affine then(const Affine& child) const {  // this * child
    if (child.identity) return *this;
    if (identity) return child;
    Affine r;
    r.identity = false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) {
        double v = j == 3 ? m[i][3] : 0.0;
        for (int k = 0; k < 3; ++k) v += m[i][k] * child.m[k][j];
        r.m[i][j] = v;
      }
    return r;
  }
  Vec3 apply(const aiVector3D& p) const {
    const double x = p.x, y = p.y, z = p.z;
    if (identity) return {x, y, z};
    return {m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3], m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3],
            m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3]};
  }
  double determinant() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
};

// ------------------------------------------------------------------ glTF materials

// Up to n numbers at `key` of object `o`, or `fallback` when absent.
std::vector<double> numbers(const Json& o, const char* key, size_t n, std::vector<double> fallback,
                            const std::string& at) {
  if (!o.contains(key)) return fallback;
  const Json& v = o.at(key);
  if (!v.is_array() || v.size() != n || !std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); }))
    throw InputError(at + key + ": expected " + std::to_string(n) + " numbers, got " + dumped(v));
  std::vector<double> out;
  for (const Json& x : v) out.push_back(x.get<double>());
  return out;
}

struct GltfMaterials {
  std::vector<Material> materials;
  std::vector<std::string> where;              // "x.gltf: materials[0] 'red'"
  std::vector<bool> base_given;                // baseColorFactor present (else the default 1 1 1)
  std::vector<std::vector<std::string>> notes;  // what is read but ignored (textures)
};

GltfMaterials gltf_materials(const std::string& path, const Json& gltf) {
  GltfMaterials out;
  if (!gltf.is_object()) throw InputError(path + ": the glTF JSON is not an object");
  const Json version = gltf.contains("asset") && gltf["asset"].is_object() ? gltf["asset"].value("version", Json())
                                                                           : Json();
  if (!version.is_string() || version.get<std::string>().rfind("2.", 0) != 0)
    throw InputError(path + ": asset.version is " + dumped(version) + "; radmesh reads glTF 2.0");
  if (!gltf.contains("materials")) return out;
  const Json& mats = gltf["materials"];
  if (!mats.is_array()) throw InputError(path + ": materials: expected an array, got " + dumped(mats));
  for (size_t i = 0; i < mats.size(); ++i) {
    const Json& m = mats[i];
    const std::string key = "materials[" + std::to_string(i) + "]";
    if (!m.is_object()) throw InputError(path + ": " + key + ": expected an object, got " + dumped(m));
    Material mat;
    mat.name = m.contains("name") && m["name"].is_string() ? m["name"].get<std::string>() : key;
    mat.file = path;
    const std::string at = path + ": " + key + " '" + shown(mat.name) + "': ";
    const Json pbr = m.value("pbrMetallicRoughness", Json::object());
    if (!pbr.is_object()) throw InputError(at + "pbrMetallicRoughness: expected an object, got " + dumped(pbr));
    const auto base = numbers(pbr, "baseColorFactor", 4, {1, 1, 1, 1}, at + "pbrMetallicRoughness.");
    const auto emissive = numbers(m, "emissiveFactor", 3, {0, 0, 0}, at);
    double strength = 1.0;
    if (m.contains("extensions") && m["extensions"].is_object() &&
        m["extensions"].contains("KHR_materials_emissive_strength")) {
      const Json& ext = m["extensions"]["KHR_materials_emissive_strength"];
      const Json s = ext.is_object() ? ext.value("emissiveStrength", Json(1.0)) : ext;
      if (!s.is_number())
        throw InputError(at + "extensions.KHR_materials_emissive_strength.emissiveStrength: expected a number, got " +
                         dumped(s));
      strength = s.get<double>();
    }
    mat.reflectance = Rgb(base[0], base[1], base[2]);
    mat.emission = Rgb(emissive[0] * strength, emissive[1] * strength, emissive[2] * strength);
    std::vector<std::string> notes;
    if (pbr.contains("baseColorTexture"))
      notes.push_back(at + "baseColorTexture is ignored: the reflectance is baseColorFactor");
    if (m.contains("emissiveTexture"))
      notes.push_back(at + "emissiveTexture is ignored: the emission is emissiveFactor");
    out.notes.push_back(std::move(notes));
    out.base_given.push_back(pbr.contains("baseColorFactor"));
    out.where.push_back(path + ": " + key + " '" + shown(mat.name) + "'");
    out.materials.push_back(std::move(mat));
  }
  return out;
}

void check_gltf_material(const Material& m, const std::string& where, bool given) {
  for (int c = 0; c < 3; ++c) {
    const double r = m.reflectance[c];
    if (!std::isfinite(r) || r < 0.0 || r >= 1.0)
      throw InputError(where + ": pbrMetallicRoughness.baseColorFactor " + format_number(m.reflectance.x) + " " +
                       format_number(m.reflectance.y) + " " + format_number(m.reflectance.z) +
                       (given ? "" : " (the glTF default: the factor is not given)") +
                       " is not a reflectance in [0, 1) (1 or more makes the radiosity system singular); set "
                       "it below 1, or give the object a material in a JSON scene");
    const double e = m.emission[c];
    if (!std::isfinite(e) || e < 0.0)
      throw InputError(where + ": emissiveFactor times emissiveStrength is " + format_number(m.emission.x) + " " +
                       format_number(m.emission.y) + " " + format_number(m.emission.z) +
                       "; the emission must be finite and >= 0");
  }
}

// ------------------------------------------------------------------ names

std::string stem_of(const std::string& path) { return fs::path(path).stem().string(); }

// A name assimp made up rather than read from the file.
bool generated_name(const std::string& n) {
  static const std::regex made(R"(^<.*>$|^nodes\[\d+\]$|^meshes\[\d+\](-\d+)?$|^\$.*)");
  return n.empty() || std::regex_match(n, made);
}

std::string format_name(const std::string& ext) {
  if (ext == ".ply") return "PLY";
  if (ext == ".stl") return "STL";
  if (ext == ".off") return "OFF";
  return "glTF";
}

struct Walker {
  const aiScene* scene;
  std::string path;
  std::string stem;
  bool gltf;
  const char* element;  // "face" or "facet"
  std::vector<int> material_of;  // assimp material -> index into the source's materials, or -1
  std::string missing;           // first mesh without a material
  SceneSource* out;
  std::string ext;
  size_t counter = 0;  // faces so far, in file order (PLY, OFF, STL)

  void walk(const aiNode* node, const Affine& parent) {
    const Affine global = parent.then(Affine::from(node->mTransformation));
    const bool mirror = !global.identity && global.determinant() < 0.0;
    const std::string node_name = node->mName.C_Str();
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
      const std::string mesh_name = mesh->mName.C_Str();
      const std::string name =
          !generated_name(node_name) ? node_name : !generated_name(mesh_name) ? mesh_name : stem;
      const int material = material_of.empty() ? -1 : material_of[mesh->mMaterialIndex];
      if (material < 0 && missing.empty())
        missing = gltf ? "mesh '" + (mesh_name.empty() ? name : mesh_name) + "' has no material"
                       : format_name(ext) + " files carry no materials";
      const std::string prefix = gltf ? path + " (mesh '" + mesh_name + "', triangle " : path + " (" + element + " ";
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        const size_t no = gltf ? f : counter++;
        RawFace raw;
        raw.name = name;
        raw.material = material;
        raw.file = prefix + std::to_string(no) + ")";
        if (face.mNumIndices < 3)
          throw InputError(raw.file + ": a " + (face.mNumIndices == 1 ? "point" : "line") +
                           ", not a surface; radmesh needs polygons of 3 or more vertices");
        raw.points.reserve(face.mNumIndices);
        if (mirror) {
          raw.points.push_back(global.apply(mesh->mVertices[face.mIndices[0]]));
          for (unsigned i = face.mNumIndices - 1; i > 0; --i)
            raw.points.push_back(global.apply(mesh->mVertices[face.mIndices[i]]));
        } else {
          for (unsigned i = 0; i < face.mNumIndices; ++i)
            raw.points.push_back(global.apply(mesh->mVertices[face.mIndices[i]]));
        }
        out->faces.push_back(std::move(raw));
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) walk(node->mChildren[c], global);
  }
};

}  // namespace

SceneSource read_assimp_source(const std::string& path, bool check_materials) {
  check_input_file(path, "a scene file");
  const std::string ext = lower_extension(path);
  const bool gltf = ext == ".gltf" || ext == ".glb";
  if (ext == ".ply") check_ply(path);
  if (ext == ".off") check_off(path);
  if (ext == ".stl") check_stl(path);

  SceneSource source;
  GltfMaterials gm;
  if (gltf) {
    const GltfFile file = read_gltf_file(path, ext == ".glb");
    gm = gltf_materials(path, file.json);
    check_gltf(path, file);
  }

  std::lock_guard<std::mutex> lock(import_mutex());
  Assimp::Importer importer;
  ErrorCapture errors;
  // Only validation: no step that triangulates, welds, reorders or splits.
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (!scene) {
    std::string e = importer.GetErrorString();
    if (e.empty()) e = "assimp cannot read it";
    if (e.find("mIndices") != std::string::npos && e.find("out of range") != std::string::npos)
      e += " (a face's vertex index is out of range: a bad index, or a truncated file)";
    if (e.find("mIndices is nullptr") != std::string::npos)
      e += " (a face with no vertices: fewer faces than the header states, a truncated file or a wrong count)";
    throw InputError(path + ": " + e);
  }
  if (!errors.messages().empty()) throw InputError(path + ": " + errors.messages().front());
  if (const std::string dropped = errors.dropped(); !dropped.empty())
    throw InputError(path + ": assimp: " + dropped + " (radmesh reads a file whole or not at all)");
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
    throw InputError(path + ": assimp read it incompletely (no scene graph)");

  Walker w;
  w.scene = scene;
  w.path = path;
  w.stem = stem_of(path);
  w.gltf = gltf;
  w.ext = ext;
  w.element = ext == ".stl" ? "facet" : "face";
  w.out = &source;
  if (gltf) {
    // assimp keeps the file's materials in order and appends a default one
    // for primitives without a material.
    w.material_of.assign(scene->mNumMaterials, -1);
    for (unsigned i = 0; i < scene->mNumMaterials && i < gm.materials.size(); ++i) {
      aiString name;
      const std::string file_name = gm.materials[i].name;
      if (scene->mMaterials[i]->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && file_name.rfind("materials[", 0) != 0 &&
          file_name != name.C_Str())
        throw InputError(gm.where[i] + ": assimp names this material '" + shown(name.C_Str()) +
                         "': cannot match assimp's materials to the file's");
      w.material_of[i] = static_cast<int>(i);
    }
  }
  w.walk(scene->mRootNode, Affine());
  if (source.faces.empty()) throw InputError(path + ": no faces (radmesh needs surfaces)");
  source.missing_material = w.missing;

  if (gltf) {
    std::vector<bool> used(gm.materials.size(), false);
    for (const RawFace& f : source.faces)
      if (f.material >= 0) used[static_cast<size_t>(f.material)] = true;
    for (size_t i = 0; i < gm.materials.size(); ++i) {
      if (!used[i] || !check_materials) continue;
      check_gltf_material(gm.materials[i], gm.where[i], gm.base_given[i]);
      source.warnings.insert(source.warnings.end(), gm.notes[i].begin(), gm.notes[i].end());
    }
    source.materials = std::move(gm.materials);
  }
  return source;
}

}  // namespace radmesh::internal
