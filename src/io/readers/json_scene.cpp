// The JSON scene file: places meshes from other files and assigns materials.
// Keys (a promise to users, see radmesh/scene_reader.h and README "Scene input"):
//   materials.NAME.reflectance [r, g, b], materials.NAME.emission [r, g, b]
//   objects[i].file, objects[i].material, objects[i].transform.{scale, rotate_deg, translate}

#include "io/readers/json_parse.h"
#include "radmesh/obj_reader.h"
#include "io/readers/scene_sources.h"
#include "core/degrees.h"
#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

namespace radmesh::internal {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keeps the file's order of materials
using internal::cos_sin_degrees;
using internal::dumped;
using internal::shown;

std::string fmt(const Rgb& v) {
  return format_number(v.x) + " " + format_number(v.y) + " " + format_number(v.z);
}

// Every error of the JSON file: "scene.json: objects[1].transform.scale: ...".
struct Context {
  std::string path;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw InputError(path + ": " + key + ": " + what);
  }
  void only_keys(const Json& o, const std::string& key, std::initializer_list<const char*> allowed) const {
    for (auto it = o.begin(); it != o.end(); ++it) {
      if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return it.key() == a; }) != allowed.end())
        continue;
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + "\"" + a + "\"";
      fail(key.empty() ? "\"" + shown(it.key()) + "\"" : key + "." + shown(it.key()), "unknown key; expected " + list);
    }
  }
  Vec3 three(const Json& v, const std::string& key) const {
    if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); }))
      fail(key, "expected 3 numbers, got " + dumped(v));
    const Vec3 r(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    if (!std::isfinite(r.x) || !std::isfinite(r.y) || !std::isfinite(r.z)) fail(key, "expected finite numbers");
    return r;
  }
};

// ------------------------------------------------------------------ transform

struct Transform {
  Vec3 scale{1.0};
  Vec3 rotate_deg{0.0};
  Vec3 translate{0.0};
  double cx = 1, sx = 0, cy = 1, sy = 0, cz = 1, sz = 0;
  bool identity = true;

  // Scale, rotate about x, then y, then z, then translate.
  Vec3 apply(const Vec3& p) const {
    if (identity) return p;
    Vec3 q = p * scale;
    q = Vec3(q.x, cx * q.y - sx * q.z, sx * q.y + cx * q.z);
    q = Vec3(cy * q.x + sy * q.z, q.y, -sy * q.x + cy * q.z);
    q = Vec3(cz * q.x - sz * q.y, sz * q.x + cz * q.y, q.z);
    return q + translate;
  }
  bool mirrors() const { return scale.x * scale.y * scale.z < 0.0; }
};

Transform parse_transform(const Context& ctx, const Json& t, const std::string& key) {
  Transform tr;
  if (!t.is_object()) ctx.fail(key, "expected an object with \"scale\", \"rotate_deg\", \"translate\", got " + dumped(t));
  ctx.only_keys(t, key, {"scale", "rotate_deg", "translate"});
  if (t.contains("scale")) {
    const Json& s = t["scale"];
    const std::string k = key + ".scale";
    if (s.is_number()) {
      tr.scale = Vec3(s.get<double>());
      if (!std::isfinite(tr.scale.x)) ctx.fail(k, "expected a finite number");
    } else if (s.is_array() && s.size() == 3 &&
               std::all_of(s.begin(), s.end(), [](const Json& x) { return x.is_number(); })) {
      tr.scale = ctx.three(s, k);
    } else {
      ctx.fail(k, "expected a number or 3 numbers, got " + dumped(s));
    }
    if (tr.scale.x == 0.0 || tr.scale.y == 0.0 || tr.scale.z == 0.0)
      ctx.fail(k, dumped(s) + " would flatten the mesh; every scale factor must be non-zero");
  }
  if (t.contains("rotate_deg")) tr.rotate_deg = ctx.three(t["rotate_deg"], key + ".rotate_deg");
  if (t.contains("translate")) tr.translate = ctx.three(t["translate"], key + ".translate");
  cos_sin_degrees(tr.rotate_deg.x, &tr.cx, &tr.sx);
  cos_sin_degrees(tr.rotate_deg.y, &tr.cy, &tr.sy);
  cos_sin_degrees(tr.rotate_deg.z, &tr.cz, &tr.sz);
  tr.identity = tr.scale == Vec3(1.0) && tr.rotate_deg == Vec3(0.0) && tr.translate == Vec3(0.0);
  return tr;
}

// ------------------------------------------------------------------ materials

// The merged material list: the JSON's, then those the files carry, by name.
class Materials {
public:
  // Returns the index of `m` (described by `where` for messages), adding it
  // when new; `at` starts the message of a clash.
  int add(const Material& m, const std::string& where, const std::string& at) {
    auto it = index_.find(m.name);
    if (it == index_.end()) {
      index_[m.name] = static_cast<int>(list_.size());
      list_.push_back(m);
      where_.push_back(where);
      return static_cast<int>(list_.size()) - 1;
    }
    const Material& old = list_[static_cast<size_t>(it->second)];
    if (old.reflectance != m.reflectance || old.emission != m.emission)
      throw InputError(at + "material '" + shown(m.name) + "' is defined twice with different values: " +
                       where_[static_cast<size_t>(it->second)] + " (reflectance " + fmt(old.reflectance) +
                       ", emission " + fmt(old.emission) + ") and " + where + " (reflectance " + fmt(m.reflectance) +
                       ", emission " + fmt(m.emission) + "); rename one");
    return it->second;
  }
  int find(const std::string& name) const {
    auto it = index_.find(name);
    return it == index_.end() ? -1 : it->second;
  }
  std::vector<Material> take() { return std::move(list_); }

private:
  std::vector<Material> list_;
  std::vector<std::string> where_;
  std::map<std::string, int> index_;
};

Material parse_material(const Context& ctx, const std::string& name, const Json& m) {
  const std::string key = "materials." + shown(name);
  if (!m.is_object()) ctx.fail(key, "expected an object with \"reflectance\" (and \"emission\"), got " + dumped(m));
  ctx.only_keys(m, key, {"reflectance", "emission"});
  if (!m.contains("reflectance")) ctx.fail(key, "missing \"reflectance\" (3 numbers in [0, 1))");
  Material mat;
  mat.name = name;
  mat.file = ctx.path;
  mat.reflectance = ctx.three(m["reflectance"], key + ".reflectance");
  for (int c = 0; c < 3; ++c)
    if (mat.reflectance[c] < 0.0 || mat.reflectance[c] >= 1.0)
      ctx.fail(key + ".reflectance", fmt(mat.reflectance) +
                                         " is outside [0, 1) (a reflectance of 1 or more makes the system singular)");
  if (m.contains("emission")) {
    mat.emission = ctx.three(m["emission"], key + ".emission");
    for (int c = 0; c < 3; ++c)
      if (mat.emission[c] < 0.0) ctx.fail(key + ".emission", fmt(mat.emission) + " must be >= 0");
  }
  return mat;
}

std::string material_where(const Material& m, const std::string& fallback) {
  if (m.file.empty()) return fallback;
  return where(m.file, m.line) + "material '" + shown(m.name) + "'";
}

}  // namespace

Scene read_json_scene(const std::string& path, const SceneOptions& options) {
  check_input_file(path, "a scene file");
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open for reading");
  Json doc;
  try {
    doc = parse_json_bounded(in, path);
  } catch (const Json::exception& e) {  // a syntax error, or a number beyond double (out_of_range.406)
    std::string m = e.what();
    const size_t close = m.find("] ");
    throw InputError(path + ": " + (close == std::string::npos ? m : m.substr(close + 2)));
  }
  const Context ctx{path};
  if (!doc.is_object())
    throw InputError(path + ": expected an object with \"materials\" and \"objects\", got " + dumped(doc));
  ctx.only_keys(doc, "", {"materials", "objects"});

  Materials materials;
  if (doc.contains("materials")) {
    const Json& ms = doc["materials"];
    if (!ms.is_object()) ctx.fail("materials", "expected an object of named materials, got " + dumped(ms));
    for (auto it = ms.begin(); it != ms.end(); ++it)
      materials.add(parse_material(ctx, it.key(), it.value()), path + ": materials." + shown(it.key()), path + ": ");
  }

  if (!doc.contains("objects")) throw InputError(path + ": missing \"objects\" (a list of {\"file\": ...})");
  const Json& objects = doc["objects"];
  if (!objects.is_array() || objects.empty())
    ctx.fail("objects", "expected a non-empty list of {\"file\": ...}, got " + dumped(objects));

  const fs::path dir = fs::path(path).parent_path();
  std::vector<RawFace> faces;
  std::vector<std::string> warnings;
  for (size_t i = 0; i < objects.size(); ++i) {
    const Json& o = objects[i];
    const std::string key = "objects[" + std::to_string(i) + "]";
    if (!o.is_object()) ctx.fail(key, "expected an object with \"file\", got " + dumped(o));
    ctx.only_keys(o, key, {"file", "material", "transform"});
    if (!o.contains("file")) ctx.fail(key, "missing \"file\"");
    if (!o["file"].is_string() || o["file"].get<std::string>().empty())
      ctx.fail(key + ".file", "expected a file name, got " + dumped(o["file"]));
    const std::string name = o["file"].get<std::string>();
    // A control character, NUL included, is no part of a file name radmesh
    // opens (the system would read up to a NUL, and a message would end there).
    if (std::any_of(name.begin(), name.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; }))
      ctx.fail(key + ".file", "a file name with a control character: " + dumped(o["file"]));
    const fs::path given(name);
    const std::string file = (given.is_absolute() ? given : dir / given).string();
    const std::string ext = lower_extension(name);
    if (ext == ".json") ctx.fail(key + ".file", "'" + name + "' is a JSON scene; a scene cannot include another");
    if (ext != ".obj" && ext != ".mgf" && !is_assimp_extension(ext))
      ctx.fail(key + ".file", "'" + name + "': unknown extension '" + ext +
                                  "'; objects can be .obj, .ply, .stl, .off, .gltf, .glb or .mgf files");
    std::error_code ec;  // a name the system cannot look up (too long, ...) is not found, not an exception
    if (!fs::exists(file, ec))
      throw IoError(path + ": " + key + ".file: '" + name + "' not found (looked for " + file + ")");

    int override_material = -1;
    if (o.contains("material")) {
      const Json& m = o["material"];
      if (!m.is_string()) ctx.fail(key + ".material", "expected a material name, got " + dumped(m));
      override_material = materials.find(m.get<std::string>());
      if (override_material < 0 || !doc.contains("materials") || !doc["materials"].contains(m.get<std::string>())) {
        std::string known;
        if (doc.contains("materials"))
          for (auto it = doc["materials"].begin(); it != doc["materials"].end(); ++it)
            known += std::string(known.empty() ? "" : ", ") + shown(it.key());
        ctx.fail(key + ".material", "unknown material " + dumped(m) + " (\"materials\" defines " +
                                        (known.empty() ? std::string("none") : known) + ")");
      }
    }
    Transform tr;
    if (o.contains("transform")) tr = parse_transform(ctx, o["transform"], key + ".transform");

    SceneSource src = ext == ".obj"   ? read_obj_source(file)
                      : ext == ".mgf" ? read_mgf_source(file, options)
                                      : read_assimp_source(file, override_material < 0);
    std::vector<int> remap(src.materials.size(), -1);
    warnings.insert(warnings.end(), src.geometry_warnings.begin(), src.geometry_warnings.end());
    if (override_material < 0) {
      if (!src.missing_material.empty())
        ctx.fail(key, "'" + name + "': " + src.missing_material + "; give the object a \"material\"");
      warnings.insert(warnings.end(), src.warnings.begin(), src.warnings.end());
    }
    const bool mirror = tr.mirrors();
    for (RawFace& f : src.faces) {
      if (override_material >= 0) {
        f.material = override_material;
      } else {
        int& r = remap[static_cast<size_t>(f.material)];
        if (r < 0) {
          const Material& m = src.materials[static_cast<size_t>(f.material)];
          r = materials.add(m, material_where(m, file), path + ": " + key + ": ");
        }
        f.material = r;
      }
      if (!tr.identity) transform_face(f, [&](const Vec3& p) { return tr.apply(p); }, mirror);
      faces.push_back(std::move(f));
    }
  }
  Scene scene = build_scene(faces, materials.take(), path, options);
  scene.report.warnings.insert(scene.report.warnings.begin(), warnings.begin(), warnings.end());
  return scene;
}

}  // namespace radmesh::internal
