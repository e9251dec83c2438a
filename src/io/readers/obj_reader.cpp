// OBJ + MTL reading. tinyobjloader parses; a line-by-line pre-scan of our own
// checks every value first, because tinyobjloader reads "nan" or "x" as 0 and
// keeps no line numbers, and we owe users a message with file:line and value.
// Numbers are read in radmesh's one syntax (text_syntax.h), and every
// coordinate tinyobjloader read is compared with what its text means: the
// value checked is the value used, or the file is refused at that line.

#include "radmesh/obj_reader.h"

#include "io/readers/scene_sources.h"
#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <tiny_obj_loader.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>

namespace radmesh {

namespace {

namespace fs = std::filesystem;

// Splits at spaces and tabs, the separators tinyobjloader knows. Any other
// control character (vertical tab, form feed, NUL, ...) is an error naming
// the line: tinyobjloader would not split there and would silently drop or
// misread the statement, shifting later indices.
std::vector<std::string> split_ws(const std::string& line, const std::string& path, int ln) {
  for (const char c : line)
    if (static_cast<unsigned char>(c) < 0x20 && c != '\t') {
      char code[8];
      std::snprintf(code, sizeof code, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
      throw InputError(where(path, ln) + "control character " + code +
                       " in the line (only spaces and tabs may separate values)");
    }
  std::vector<std::string> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

using internal::read_number;
using internal::read_whole;
using internal::reads_as_double;
using internal::shown;

// A statement of an OBJ or MTL file: its text and the line it starts on.
// A line ending in a backslash goes on in the next one (the formats'
// continuation; tinyobjloader knows none and read such a face as an
// error); the backslash becomes a space.
struct Line {
  std::string text;
  int number = 0;
};
struct Lines {
  std::vector<Line> lines;
  bool continued = false;  // some statement spans several lines
  // The statements joined, one a line, for tinyobjloader (which knows no
  // continuation).
  std::string joined() const {
    std::string out;
    for (const Line& l : lines) (out += l.text) += '\n';
    return out;
  }
  bool rewritten = false;  // some statement was changed for tinyobjloader (ObjScan::long_faces, mtllib)
  bool byte_order_mark = false;  // the file starts with one (tinyobjloader would read it as part of a statement)
};

Lines read_lines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open for reading");
  Lines out;
  bool open = false;  // the last statement ended in a backslash
  int number = 0;
  for (std::string l; std::getline(in, l);) {
    ++number;
    if (number == 1) out.byte_order_mark = internal::strip_byte_order_mark(l);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    // A comment does not go on: "# made in C:\models\" would swallow the
    // statement after it.
    const size_t first = l.find_first_not_of(" \t");
    const bool comment = !open && first != std::string::npos && l[first] == '#';
    const bool goes_on = !comment && !l.empty() && l.back() == '\\';
    if (goes_on) l.back() = ' ';
    if (open) {
      out.lines.back().text += l;
      out.continued = true;
    } else {
      out.lines.push_back({std::move(l), number});
    }
    open = goes_on;
  }
  if (in.bad()) throw IoError(path + ": read error");
  return out;
}

// Per material: where it and its Kd/Ke are in the MTL file, and their
// values (read here, not by tinyobjloader, which reads "nan" as 0 and one
// value "Kd 0.5" as (0.5, 0, 0) where the MTL format means (0.5, 0.5, 0.5)).
struct MtlInfo {
  std::string file;
  int line = 0, kd_line = 0, ke_line = 0;
  Rgb kd{0.0}, ke{0.0};
};

void scan_mtl(const std::string& path, std::map<std::string, MtlInfo>* info) {
  const std::vector<Line> lines = read_lines(path).lines;
  std::string current;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int ln = lines[i].number;
    const auto tok = split_ws(lines[i].text, path, ln);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (tok[0] == "newmtl") {
      if (tok.size() < 2) throw InputError(where(path, ln) + "newmtl without a name");
      // tinyobjloader names the material with the rest of the line after
      // "newmtl" and one separator; an OBJ's usemtl names one word.
      const std::string& text = lines[i].text;
      std::string rest = text.substr(text.find_first_not_of(" \t") + 7);
      rest.erase(rest.find_last_not_of(" \t") + 1);
      if (tok.size() != 2 || rest != tok[1])
        throw InputError(where(path, ln) + "material name '" + shown(rest) +
                         "' is not one word after one space: a usemtl names one word (write the name without "
                         "spaces)");
      current = tok[1];
      const auto old = info->find(current);
      if (old != info->end())
        throw InputError(where(path, ln) + "material '" + shown(current) + "' is defined again (first at " +
                         where(old->second.file, old->second.line) + "one name must mean one material)");
      (*info)[current] = {path, ln, 0, 0, Rgb(0.0), Rgb(0.0)};
    } else if (tok[0] == "Kd" || tok[0] == "Ke") {
      if (current.empty()) throw InputError(where(path, ln) + tok[0] + " before any newmtl");
      if (tok.size() != 4 && tok.size() != 2)
        throw InputError(where(path, ln) + tok[0] + " needs 3 numbers (or 1), got '" + lines[i].text + "'");
      Rgb value(0.0);
      for (size_t k = 1; k < tok.size(); ++k) {
        double v = 0.0;
        const std::string why = read_number(tok[k], &v);
        if (!why.empty()) throw InputError(where(path, ln) + tok[0] + " value '" + shown(tok[k]) + "' " + why);
        value[static_cast<int>(k) - 1] = v;
      }
      if (tok.size() == 2) value = Rgb(value.x);  // one value: grey
      MtlInfo& m = (*info)[current];
      if (tok[0] == "Kd") {
        m.kd_line = ln;
        m.kd = value;
      } else {
        m.ke_line = ln;
        m.ke = value;
      }
    }
  }
}

// tinyobjloader counts a face's vertices in an unsigned char: a face of 300
// vertices comes out with 44 (300 - 256), the rest of it dropped without a
// word. Such a face is
// given to it as its first three vertices, which keeps its place, object
// and material, and its vertices are taken from the scan.
constexpr size_t kTinyobjMostVertices = 255;

struct ObjScan {
  std::vector<int> face_lines;  // line of each f, in file order
  // Faces of more than kTinyobjMostVertices vertices: face number -> its
  // vertices (0-based indices into the v statements).
  std::map<size_t, std::vector<long>> long_faces;
  std::map<std::string, MtlInfo> materials;
  std::string joined;  // the statements, where some span several lines or were rewritten; else empty
  // Per v statement: its line, and x, y, z as their text means (compared
  // with what tinyobjloader read).
  std::vector<int> vertex_lines;
  std::vector<double> coordinates;
};

// The file a material library name refers to, as one spelling ("m.mtl" and
// "./m.mtl" are one library).
std::string library_key(const fs::path& file) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(file, ec);
  return (ec ? file.lexically_normal() : canonical).string();
}

ObjScan scan_obj(const std::string& path) {
  ObjScan scan;
  Lines read = read_lines(path);
  std::vector<Line>& lines = read.lines;
  const fs::path dir = fs::path(path).parent_path();
  long vertices = 0;
  std::set<std::string> used;
  std::set<std::string> libraries;
  std::map<std::string, int> used_line;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int ln = lines[i].number;
    const auto tok = split_ws(lines[i].text, path, ln);
    if (tok.empty() || tok[0][0] == '#') continue;
    const std::string& key = tok[0];
    if (key == "v") {
      // x y z, x y z w, or x y z r g b (a colour per vertex, as MeshLab
      // writes: read, not used).
      if (tok.size() < 4 || tok.size() == 6 || tok.size() > 7)
        throw InputError(where(path, ln) + "vertex needs 3 coordinates (then a weight, or 3 colour values), got '" +
                         lines[i].text + "'");
      for (size_t k = 1; k < tok.size(); ++k) {
        double v = 0.0;
        const std::string why = read_number(tok[k], &v);
        if (!why.empty())
          throw InputError(where(path, ln) + (k <= 3 ? "coordinate '" : "vertex value '") + shown(tok[k]) + "' " +
                           why);
        if (k <= 3) scan.coordinates.push_back(v);
      }
      scan.vertex_lines.push_back(ln);
      ++vertices;
    } else if (key == "f") {
      if (tok.size() < 4)
        throw InputError(where(path, ln) + "face needs at least 3 vertices, got '" + shown(lines[i].text) + "'");
      const bool long_face = tok.size() - 1 > kTinyobjMostVertices;
      std::vector<long> indices;
      for (size_t k = 1; k < tok.size(); ++k) {
        // v, v/vt, v//vn or v/vt/vn: each a whole number (tinyobjloader
        // reads them with atoi, which takes "2x" as 2 and 4294967297 as 1).
        const std::string& corner = tok[k];
        // Its parts between slashes (no copies: this runs per face corner).
        std::string_view parts[3];
        size_t count = 0;
        for (size_t from = 0;; ++count) {
          const size_t slash = corner.find('/', from);
          if (count < 3) parts[count] = std::string_view(corner).substr(from, slash == std::string::npos ? slash : slash - from);
          if (slash == std::string::npos) break;
          from = slash + 1;
        }
        ++count;
        const std::string_view idx = parts[0];
        long long v = 0;
        std::string why = read_whole(idx, true, &v);
        if (why.empty() && v == 0) why = "is 0 (OBJ indices start at 1)";
        if (why.empty() && count > 3) why = "has more than 3 parts";
        for (size_t p = 1; why.empty() && p < count; ++p) {
          long long other = 0;
          if (!(p == 1 && count == 3 && parts[1].empty())) why = read_whole(parts[p], true, &other);
          if (why.empty() && other == 0 && !parts[p].empty()) why = "is 0 (OBJ indices start at 1)";
        }
        if (!why.empty())
          throw InputError(where(path, ln) + "face vertex index '" + shown(corner) + "' " + why);
        const long long abs = v > 0 ? v : vertices + v + 1;
        if (abs < 1 || abs > vertices)
          throw InputError(where(path, ln) + "face vertex index " + std::string(idx) + " is out of range (" +
                           std::to_string(vertices) + " vertices defined so far)");
        if (long_face) indices.push_back(static_cast<long>(abs - 1));
      }
      if (long_face) {
        scan.long_faces[scan.face_lines.size()] = std::move(indices);
        lines[i].text = "f " + tok[1] + " " + tok[2] + " " + tok[3];
        read.rewritten = true;
      }
      scan.face_lines.push_back(ln);
    } else if (key == "mtllib") {
      // tinyobjloader loads the first library of a statement that it can
      // open: each is given to it in a statement of its own.
      if (tok.size() > 2) {
        std::string own;
        for (size_t k = 1; k < tok.size(); ++k) own += (k > 1 ? "\nmtllib " : "mtllib ") + tok[k];
        lines[i].text = own;
        read.rewritten = true;
      }
      for (size_t k = 1; k < tok.size(); ++k) {
        const fs::path mtl = dir / tok[k];
        std::error_code ec;  // a name the system cannot look up (too long, ...) is not found, not an exception
        if (!fs::exists(mtl, ec))
          throw InputError(where(path, ln) + "material library '" + tok[k] + "' not found (looked for " +
                           mtl.string() + ")");
        try {
          internal::check_input_file(mtl.string(), "a material library");
        } catch (const IoError& e) {
          throw InputError(where(path, ln) + "material library '" + tok[k] + "': " + e.what());
        }
        // A library named again (by another spelling too) is read once.
        if (libraries.insert(library_key(mtl)).second) scan_mtl(mtl.string(), &scan.materials);
      }
    } else if (key == "usemtl") {
      if (tok.size() < 2) throw InputError(where(path, ln) + "usemtl without a name");
      if (tok.size() > 2)
        throw InputError(where(path, ln) + "usemtl names one material, got '" + shown(lines[i].text) +
                         "' (a material name has no spaces)");
      if (!used.count(tok[1])) used_line[tok[1]] = ln;
      used.insert(tok[1]);
    } else if (key == "vt" || key == "vn" || key == "o" || key == "g" || key == "s" || key == "l" ||
               key == "p") {
      // accepted; texture coordinates, normals, lines and points are not used
    } else {
      throw InputError(where(path, ln) + "unknown OBJ statement '" + shown(key) + "'");
    }
  }
  for (const std::string& name : used)
    if (!scan.materials.count(name))
      throw InputError(where(path, used_line[name]) + "material '" + name +
                       "' is not defined in any mtllib file");
  if (read.continued || read.rewritten || read.byte_order_mark) scan.joined = read.joined();
  return scan;
}

}  // namespace

namespace internal {

SceneSource read_obj_source(const std::string& path) {
  check_input_file(path, "an OBJ file");
  const ObjScan scan = scan_obj(path);

  // Material libraries are found as the scan found them (next to the OBJ,
  // or at an absolute path): tinyobjloader's own reader prefixes the OBJ's
  // directory to an absolute path too, and a scene read from another
  // directory lost its materials ("face has no material").
  // A library named again, by any spelling, is read once (as the scan read it).
  struct LibraryReader : tinyobj::MaterialReader {
    fs::path dir;
    std::set<std::string> read;
    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* names, std::string* warn, std::string* err) override {
      const fs::path file = dir / name;
      if (!std::ifstream(file)) {
        if (err) *err += "cannot open material library " + file.string() + "\n";
        return false;
      }
      if (!read.insert(library_key(file)).second) return true;
      std::istringstream in(read_lines(file.string()).joined());
      tinyobj::LoadMtl(names, materials, &in, warn, err);
      return true;
    }
  } library;
  library.dir = fs::path(path).parent_path();
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> tiny_materials;
  std::string warn, err;
  std::ifstream file(path);
  std::istringstream joined(scan.joined);
  std::istream& obj = scan.joined.empty() ? static_cast<std::istream&>(file) : joined;
  if (!tinyobj::LoadObj(&attrib, &shapes, &tiny_materials, &warn, &err, &obj, &library, false, false))
    throw InputError(path + ": " + (err.empty() ? "cannot parse" : err));

  // The value checked is the value used: each coordinate tinyobjloader read
  // (with a parser of its own) is the one its text means.
  if (attrib.vertices.size() != scan.coordinates.size())
    throw InputError(path + ": tinyobjloader read " + std::to_string(attrib.vertices.size() / 3) +
                     " vertices, the file has " + std::to_string(scan.vertex_lines.size()) + " v statements");
  for (size_t i = 0; i < scan.coordinates.size(); ++i)
    if (!reads_as_double(attrib.vertices[i], scan.coordinates[i]))
      throw InputError(where(path, scan.vertex_lines[i / 3]) + "coordinate " + std::string(1, "xyz"[i % 3]) + " = " +
                       format_number(scan.coordinates[i]) + " reads as " + format_number(attrib.vertices[i]) +
                       " in the OBJ parser (tinyobjloader); write it with fewer digits");

  // Materials in tinyobjloader's order (its faces index them), with the
  // values our own scan read and checked.
  SceneSource source;
  std::vector<Material> materials;
  for (const auto& m : tiny_materials) {
    Material mat;
    mat.name = m.name;
    const auto it = scan.materials.find(m.name);
    if (it == scan.materials.end())
      throw InputError(path + ": material '" + shown(m.name) +
                       "' was read by tinyobjloader but not by radmesh's scan of the material libraries");
    const MtlInfo& info = it->second;
    mat.file = info.file;
    mat.line = info.line;
    mat.reflectance_line = info.kd_line;
    mat.emission_line = info.ke_line;
    mat.reflectance = info.kd;
    mat.emission = info.ke;
    if (info.kd_line == 0)
      source.warnings.push_back(where(info.file, info.line) + "material '" + m.name +
                                "' has no Kd: reflectance 0 (it absorbs all light it receives)");
    materials.push_back(std::move(mat));
  }

  std::vector<RawFace>& faces = source.faces;
  size_t face_no = 0;
  for (const auto& shape : shapes) {
    size_t offset = 0;
    for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f, ++face_no) {
      RawFace face;
      face.name = shape.name.empty() ? fs::path(path).stem().string() : shape.name;  // no o/g: the file's stem
      face.material = shape.mesh.material_ids[f];
      face.file = path;
      face.line = face_no < scan.face_lines.size() ? scan.face_lines[face_no] : 0;
      auto add_point = [&](size_t vi) {
        face.points.emplace_back(attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]);
      };
      const size_t nv = shape.mesh.num_face_vertices[f];
      const auto long_face = scan.long_faces.find(face_no);
      if (long_face != scan.long_faces.end())
        for (const long vi : long_face->second) add_point(static_cast<size_t>(vi));
      else
        for (size_t k = 0; k < nv; ++k) add_point(static_cast<size_t>(shape.mesh.indices[offset + k].vertex_index));
      offset += nv;
      if (face.material < 0 && source.missing_material.empty())
        source.missing_material =
            where(path, face.line) + "face '" + face.name + "' has no material (no usemtl before it)";
      faces.push_back(std::move(face));
    }
  }
  if (faces.size() != scan.face_lines.size())
    throw InputError(path + ": read " + std::to_string(faces.size()) + " faces but the file has " +
                     std::to_string(scan.face_lines.size()) + " face lines");
  source.materials = std::move(materials);
  return source;
}

}  // namespace internal

Scene read_obj_scene(const std::string& path, const SceneOptions& options) {
  internal::SceneSource source = internal::read_obj_source(path);
  Scene scene = build_scene(source.faces, std::move(source.materials), path, options);
  scene.report.warnings.insert(scene.report.warnings.begin(), source.warnings.begin(), source.warnings.end());
  return scene;
}

}  // namespace radmesh
