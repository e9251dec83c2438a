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

#include "io/readers/json_parse.h"
#include "io/readers/scene_sources.h"
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
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <regex>
#include <vector>
#include <sstream>
#include <string_view>
#include <map>

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
    // "Error, T0: text" -> "text"
    const size_t colon = m.find(": ");
    if (m.rfind("Error", 0) == 0 && colon != std::string::npos) m = m.substr(colon + 2);
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
  }
  ~ErrorCapture() {
    Assimp::DefaultLogger::get()->detachStream(&stream_, Assimp::Logger::Err);
    if (created_) Assimp::DefaultLogger::kill();
  }
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;
  const std::vector<std::string>& messages() const { return stream_.messages; }

private:
  bool created_ = false;
  ErrorCollector stream_;
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

std::string dump(const Json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

// ------------------------------------------------------------------ glTF materials

// The glTF JSON: the .gltf file itself, or the JSON chunk of a .glb.
Json read_gltf_json(const std::string& path, bool binary) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open for reading");
  std::string text;
  if (binary) {
    char header[20];
    if (!in.read(header, 20)) throw InputError(path + ": too short for a .glb file");
    uint32_t magic, length, type;
    std::memcpy(&magic, header, 4);
    std::memcpy(&length, header + 12, 4);
    std::memcpy(&type, header + 16, 4);
    if (magic != 0x46546C67u || type != 0x4E4F534Au)
      throw InputError(path + ": not a binary glTF file (no 'glTF' header and JSON chunk)");
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec || 20.0 + length > static_cast<double>(size))  // not an allocation the header alone decides
      throw InputError(path + ": JSON chunk of a stated " + std::to_string(length) + " bytes, longer than the file");
    text.resize(length);
    if (!in.read(text.data(), static_cast<std::streamsize>(length)))
      throw InputError(path + ": JSON chunk shorter than its stated " + std::to_string(length) + " bytes");
  } else {
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  try {
    return parse_json_bounded(text, path, /*unique_keys=*/false);  // as assimp reads it: the last one stands
  } catch (const Json::exception& e) {
    std::string m = e.what();
    const size_t close = m.find("] ");
    throw InputError(path + ": " + (close == std::string::npos ? m : m.substr(close + 2)));
  }
}

// Up to n numbers at `key` of object `o`, or `fallback` when absent.
std::vector<double> numbers(const Json& o, const char* key, size_t n, std::vector<double> fallback,
                            const std::string& at) {
  if (!o.contains(key)) return fallback;
  const Json& v = o.at(key);
  if (!v.is_array() || v.size() != n || !std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); }))
    throw InputError(at + key + ": expected " + std::to_string(n) + " numbers, got " + dump(v));
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
    throw InputError(path + ": asset.version is " + dump(version) + "; radmesh reads glTF 2.0");
  if (!gltf.contains("materials")) return out;
  const Json& mats = gltf["materials"];
  if (!mats.is_array()) throw InputError(path + ": materials: expected an array, got " + dump(mats));
  for (size_t i = 0; i < mats.size(); ++i) {
    const Json& m = mats[i];
    const std::string key = "materials[" + std::to_string(i) + "]";
    if (!m.is_object()) throw InputError(path + ": " + key + ": expected an object, got " + dump(m));
    Material mat;
    mat.name = m.contains("name") && m["name"].is_string() ? m["name"].get<std::string>() : key;
    mat.file = path;
    const std::string at = path + ": " + key + " '" + mat.name + "': ";
    const Json pbr = m.value("pbrMetallicRoughness", Json::object());
    if (!pbr.is_object()) throw InputError(at + "pbrMetallicRoughness: expected an object, got " + dump(pbr));
    const auto base = numbers(pbr, "baseColorFactor", 4, {1, 1, 1, 1}, at + "pbrMetallicRoughness.");
    const auto emissive = numbers(m, "emissiveFactor", 3, {0, 0, 0}, at);
    double strength = 1.0;
    if (m.contains("extensions") && m["extensions"].is_object() &&
        m["extensions"].contains("KHR_materials_emissive_strength")) {
      const Json& ext = m["extensions"]["KHR_materials_emissive_strength"];
      const Json s = ext.is_object() ? ext.value("emissiveStrength", Json(1.0)) : ext;
      if (!s.is_number())
        throw InputError(at + "extensions.KHR_materials_emissive_strength.emissiveStrength: expected a number, got " +
                         dump(s));
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
    out.where.push_back(path + ": " + key + " '" + mat.name + "'");
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

// One property of a PLY element, as the body is checked against it.
struct PlyProperty {
  bool list = false;
  int bytes = 0;        // binary: a value's (a list's items')
  int count_bytes = 0;  // binary: a list's count
};

// Per element: its count and its properties.
using PlyLayout = std::vector<std::pair<double, std::vector<PlyProperty>>>;

template <class Layout>
double element_total(const Layout& layout) {
  double n = 0.0;
  for (const auto& e : layout) n += e.first;
  return n;
}

// A word of a header as it may be printed: control bytes as \xNN, at most 40 characters.
std::string shown(const std::string& word) {
  std::string out;
  for (const char c : word.substr(0, 40)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", static_cast<unsigned>(u));
      out += hex;
    } else {
      out += c;
    }
  }
  return out;
}

// What a PLY header declares, and where it ends.
struct PlyHeader {
  bool binary = false, big_endian = false;
  double bytes_needed = 0.0;  // at least, for the declared elements
  PlyLayout layout;           // the body is checked against it
  size_t read = 0;            // bytes of the header
  int ln = 0;                 // lines of the header
};

// Reads a PLY header: known keywords and types only, end_header within the
// first 64 KiB. Throws InputError naming the header line.
PlyHeader read_ply_header(std::istream& in, const std::string& path) {
  static const std::map<std::string, int> kTypeBytes = {
      {"char", 1},   {"uchar", 1},   {"int8", 1},   {"uint8", 1},   {"short", 2},   {"ushort", 2},
      {"int16", 2},  {"uint16", 2},  {"int", 4},    {"uint", 4},    {"int32", 4},   {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  auto bad = [&](int line, const std::string& what) {
    throw InputError(path + ": PLY header line " + std::to_string(line) + ": " + what);
  };
  PlyHeader h;
  bool ended = false;
  double element_count = 0.0, element_bytes = 0.0;
  auto close_element = [&] { h.bytes_needed += element_count * element_bytes; };
  std::string line;
  while (!ended && h.read < 65536 && std::getline(in, line)) {
    h.read += line.size() + 1;
    ++h.ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    const std::string head = w.empty() ? "" : w[0];
    if (h.ln == 1) {
      if (head != "ply" || w.size() != 1) bad(1, "a PLY file starts with the line 'ply'");
    } else if (head == "format") {
      if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        bad(h.ln, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      h.binary = w[1] != "ascii";
      h.big_endian = w[1] == "binary_big_endian";
    } else if (head == "comment" || head == "obj_info") {
    } else if (head == "element") {
      double count = -1.0;
      if (w.size() == 3) {
        char* end = nullptr;
        count = std::strtod(w[2].c_str(), &end);
        if (*end != '\0' || !(count >= 0.0) || count != std::floor(count)) count = -1.0;
      }
      if (count < 0.0) bad(h.ln, "expected 'element NAME COUNT' with a whole COUNT >= 0");
      close_element();
      element_count = count;
      element_bytes = 0.0;
      h.layout.push_back({count, {}});
    } else if (head == "property") {
      const bool list = w.size() == 5 && w[1] == "list";
      if (!(list || w.size() == 3)) bad(h.ln, "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      for (size_t i = list ? 2 : 1; i + 1 < w.size(); ++i)
        if (!kTypeBytes.count(w[i])) bad(h.ln, "unknown property type '" + shown(w[i]) + "'");
      element_bytes += h.binary ? kTypeBytes.at(w[list ? 2 : 1]) : 2.0;
      if (h.layout.empty()) bad(h.ln, "'property' before any 'element'");
      h.layout.back().second.push_back({list, kTypeBytes.at(w[list ? 3 : 1]), list ? kTypeBytes.at(w[2]) : 0});
    } else if (head == "end_header") {
      ended = true;
    } else {
      bad(h.ln, "unexpected '" + shown(line) + "'");
    }
  }
  if (!ended) bad(h.ln, "no end_header line in the first 64 KiB");
  close_element();
  return h;
}

// Data after the declared elements is a wrong count whose rest assimp
// drops without a word (a header declaring 1 face over a file of 2 gives
// one triangle, half the square).
[[noreturn]] void more_than_declared(const std::string& path, const PlyLayout& layout, const std::string& what) {
  throw InputError(path + ": " + what + " after the " + std::to_string(static_cast<long long>(element_total(layout))) +
                   " elements its PLY header declares (a wrong count would drop them)");
}

// A binary body's length, walking its lists in one pass (a list's count
// read in the file's byte order): anything past it is more than declared.
void check_binary_ply_body(std::istream& in, const std::string& path, const PlyHeader& header, double file_size) {
  const bool big_endian = header.big_endian;
  double at = static_cast<double>(header.read);
  unsigned char count[8] = {};
  for (const auto& [n, props] : header.layout) {
    const bool has_list = std::any_of(props.begin(), props.end(), [](const PlyProperty& p) { return p.list; });
    if (!has_list) {
      double fixed = 0.0;
      for (const PlyProperty& p : props) fixed += p.bytes;
      at += n * fixed;
      if (at > file_size) return;  // short: said above
      in.seekg(static_cast<std::streamoff>(at));
      continue;
    }
    for (double k = 0.0; k < n; ++k)
      for (const PlyProperty& p : props) {
        if (!p.list) {
          in.ignore(p.bytes);
          at += p.bytes;
          continue;
        }
        if (!in.read(reinterpret_cast<char*>(count), p.count_bytes)) return;  // short: assimp says so
        uint64_t items = 0;
        for (int b = 0; b < p.count_bytes; ++b)
          items |= static_cast<uint64_t>(count[big_endian ? p.count_bytes - 1 - b : b]) << (8 * b);
        const double skip = static_cast<double>(items) * p.bytes;
        at += p.count_bytes + skip;
        if (at > file_size) return;  // short: assimp says so
        in.ignore(static_cast<std::streamsize>(skip));
      }
  }
  if (file_size > at)
    more_than_declared(path, header.layout, std::to_string(static_cast<long long>(file_size - at)) + " bytes");
}

// An ASCII body has one line per element: fewer lines is a truncated file
// (assimp reads what is there and reports something else), and a list's
// count cannot exceed the values left on its line (assimp 5.2 allocates
// what a count says, and a count that is a long run of digits asks for
// gigabytes).
void check_ascii_ply_body(std::istream& in, const std::string& path, const PlyHeader& header) {
  const PlyLayout& layout = header.layout;
  int ln = header.ln;
  std::string line;
  const double elements = element_total(layout);
  double lines = 0.0;
  std::vector<std::string_view> tokens;
  for (const auto& [count, props] : layout)
    for (double k = 0.0; k < count; ++k) {
      do {
        if (!std::getline(in, line))
          throw InputError(path + ": the PLY header declares " + std::to_string(static_cast<long long>(elements)) +
                           " elements, but the file has " + std::to_string(static_cast<long long>(lines)) +
                           " lines after its header (truncated, or a wrong count)");
        ++ln;
      } while (line.find_first_not_of(" \t\r") == std::string::npos);
      ++lines;
      tokens.clear();
      for (size_t b = line.find_first_not_of(" \t\r"); b != std::string::npos; b = line.find_first_not_of(" \t\r", b)) {
        const size_t e = line.find_first_of(" \t\r", b);
        tokens.push_back(std::string_view(line).substr(b, e == std::string::npos ? std::string::npos : e - b));
        b = e;
      }
      size_t at = 0;
      for (const PlyProperty& p : props) {
        if (at >= tokens.size()) break;  // too few values: assimp's own message names them
        if (!p.list) {
          ++at;
          continue;
        }
        const std::string n(tokens[at++]);
        char* end = nullptr;
        const double values = std::strtod(n.c_str(), &end);
        if (*end != '\0' || !(values >= 0.0) || values > static_cast<double>(tokens.size() - at))
          throw InputError(path + ": line " + std::to_string(ln) + ": a list of '" + shown(n) + "' values, but the line has " +
                           std::to_string(tokens.size() - at) + " more");
        at += static_cast<size_t>(values);
      }
    }
  while (std::getline(in, line)) {
    ++ln;
    if (line.find_first_not_of(" \t\r") != std::string::npos)
      more_than_declared(path, layout, "line " + std::to_string(ln) + " holds data");
  }
}

// Checks a PLY file before assimp sees it: assimp 5.2 loops without end on
// some malformed headers (an unknown property type, no end_header), and
// allocates what a header's element counts declare before reading a byte of
// the body. So: known keywords and types only, end_header within the first
// 64 KiB, every element count within what the rest of the file can hold
// (at least one byte per value in binary, two per value in ASCII: a digit and
// a separator), and no data past the declared elements. Throws InputError
// naming the header line.
void check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto file_size = static_cast<double>(fs::file_size(path, ec));
  const PlyHeader header = read_ply_header(in, path);
  const double body = file_size - static_cast<double>(header.read);
  if (header.bytes_needed > body)
    throw InputError(path + ": the PLY header declares elements needing at least " +
                     std::to_string(static_cast<long long>(std::min(header.bytes_needed, 9e18))) +
                     " bytes, but the file has " + std::to_string(static_cast<long long>(body)) +
                     " after its header (truncated, or a wrong count)");
  if (header.binary)
    check_binary_ply_body(in, path, header, file_size);
  else
    check_ascii_ply_body(in, path, header);
}

// A binary STL must be as long as its facet count says, and an ASCII STL
// (a file starting with "solid" that is not a binary STL of its size) must
// close every facet and end with "endsolid": assimp reads a truncated one
// up to its last whole facet without a word.
void check_stl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  char header[84] = {};
  in.read(header, sizeof header);
  const auto got = static_cast<size_t>(in.gcount());
  uint32_t count = 0;
  if (got == sizeof header) std::memcpy(&count, header + 80, 4);
  if (!ec && got == sizeof header && size == 84 + 50 * static_cast<uintmax_t>(count)) return;  // binary
  if (std::string(header, std::min<size_t>(got, 5)) != "solid") {
    if (ec || got < sizeof header)
      throw InputError(path + ": " + std::to_string(got) + " bytes: too short for a binary STL (84-byte header)");
    throw InputError(path + ": a binary STL stating " + std::to_string(count) + " facets needs " +
                     std::to_string(84 + 50 * static_cast<uintmax_t>(count)) + " bytes, the file has " +
                     std::to_string(size) + " (truncated, or not an STL file)");
  }
  in.clear();
  in.seekg(0);
  std::string line;
  int ln = 0, open_at = 0;
  bool ended = false;  // the last non-blank line starts with "endsolid"
  while (std::getline(in, line)) {  // no stream per line: a million facets are 7 M lines
    ++ln;
    const size_t b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos) continue;
    const size_t e = line.find_first_of(" \t\r", b);
    const std::string_view head = std::string_view(line).substr(b, e == std::string::npos ? std::string::npos : e - b);
    ended = head == "endsolid";
    if (head == "facet") {
      if (open_at > 0)
        throw InputError(path + ": line " + std::to_string(ln) + ": 'facet' before the facet of line " +
                         std::to_string(open_at) + " has its 'endfacet'");
      open_at = ln;
    } else if (head == "endfacet") {
      open_at = 0;
    }
  }
  if (open_at > 0)
    throw InputError(path + ": the facet of line " + std::to_string(open_at) +
                     " has no 'endfacet' (truncated file)");
  if (!ended) throw InputError(path + ": no 'endsolid' at the end (truncated file)");
}

// Checks an OFF header before assimp sees it: assimp 5.2 allocates the
// arrays its vertex and face counts declare before reading the body (a
// face count of many digits asks for gigabytes). The counts must be whole
// numbers, and the rest of the file long enough for them: 3 numbers a
// vertex, at least 4 a face (its size and 3 indices), each number at least
// one character and a separator. Throws InputError naming the header line.
void check_off_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto file_size = static_cast<double>(fs::file_size(path, ec));
  std::string head(size_t{1} << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  size_t pos = 0;
  int line = 1;
  auto space = [&](size_t i) { return std::isspace(static_cast<unsigned char>(head[i])) != 0; };
  auto next_word = [&] {  // skipping blanks and # comments
    while (pos < head.size()) {
      if (head[pos] == '#') {
        while (pos < head.size() && head[pos] != '\n') ++pos;
      } else if (space(pos)) {
        if (head[pos] == '\n') ++line;
        ++pos;
      } else {
        break;
      }
    }
    const size_t begin = pos;
    while (pos < head.size() && !space(pos) && head[pos] != '#') ++pos;
    return head.substr(begin, pos - begin);
  };
  auto bad = [&](const std::string& what) {
    throw InputError(path + ": OFF header line " + std::to_string(line) + ": " + what);
  };
  const std::string keyword = next_word();
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
    bad("expected the keyword OFF, got '" + shown(keyword) + "'");
  if (keyword.find('n') != std::string::npos) next_word();  // nOFF: the dimension comes first
  double counts[2];
  for (double& count : counts) {
    const std::string word = next_word();
    if (word.empty() || word.find_first_not_of("0123456789") != std::string::npos)
      bad("expected the vertex and face counts as whole numbers, got '" + shown(word) + "'");
    count = std::strtod(word.c_str(), nullptr);
  }
  const double numbers = 3.0 * counts[0] + 4.0 * counts[1];
  const double body = file_size - static_cast<double>(pos);
  if (2.0 * numbers - 1.0 > body)
    bad(format_number(counts[0]) + " vertices and " + format_number(counts[1]) + " faces need at least " +
        format_number(2.0 * numbers - 1.0) + " bytes, the file has " + format_number(body) +
        " after the counts (truncated, or a wrong count)");
}

}  // namespace

SceneSource read_assimp_source(const std::string& path, bool check_materials) {
  check_input_file(path, "a scene file");
  const std::string ext = lower_extension(path);
  const bool gltf = ext == ".gltf" || ext == ".glb";
  if (ext == ".ply") check_ply_header(path);
  if (ext == ".off") check_off_header(path);
  if (ext == ".stl") check_stl(path);

  SceneSource source;
  GltfMaterials gm;
  if (gltf) gm = gltf_materials(path, read_gltf_json(path, ext == ".glb"));

  std::lock_guard<std::mutex> lock(import_mutex());
  Assimp::Importer importer;
  ErrorCapture errors;
  // Only validation: no step that triangulates, welds, reorders or splits.
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  // assimp 5.2's OFF reader says "Faces with zero indices aren't allowed" of
  // a face of no vertex and of one of more than 9 alike (a round table top
  // of 12), and drops it: the import then fails, or goes on without it.
  const std::string logged = errors.messages().empty() ? "" : errors.messages().front();
  if (logged == "OFF: Faces with zero indices aren't allowed")
    throw InputError(path + ": OFF: a face has no vertex or more than 9, which assimp's OFF reader refuses (write "
                            "the mesh as OBJ or PLY: they take faces of any size)");
  if (!scene) {
    std::string e = importer.GetErrorString();
    if (e.empty()) e = "assimp cannot read it";
    if (e.find("mIndices") != std::string::npos && e.find("out of range") != std::string::npos)
      e += " (a face's vertex index is out of range: a bad index, or a truncated file)";
    if (e.find("mIndices is nullptr") != std::string::npos)
      e += " (a face with no vertices: fewer faces than the header states, a truncated file or a wrong count)";
    throw InputError(path + ": " + e);
  }
  if (!logged.empty()) throw InputError(path + ": " + logged);
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
        throw InputError(gm.where[i] + ": assimp names this material '" + name.C_Str() +
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
