// libFuzzer target: number syntax across the text readers. The first byte
// picks a reader and a place: an OBJ coordinate or face index, an MTL Kd
// value, an ASCII PLY float or double coordinate, face index or list count,
// an OFF coordinate or face index, an ASCII STL coordinate, a JSON scene's
// translation, a probe file's coordinate. The rest, mapped onto the
// characters numbers are made of (digits, '.', 'e', signs, the letters of
// hex, nan and inf, ','; a second byte with its high bit set inserts a run
// of zeros), is spliced into a valid file as that one number. The reader
// must refuse the file with a radmesh error, or read the value the token
// means, to the format's precision; a token outside the format's syntax
// that is read at all, or one read as another value, is a defect. The
// syntax is checked here by regular expressions of its own, not by the
// readers' parser: radmesh's for the text formats (docs/scenes.md), JSON's
// for JSON.

#include "fuzz/fuzz_util.h"
#include "radmesh/probe_file.h"
#include "radmesh/scene_reader.h"

#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <regex>
#include <string>

namespace {

using namespace radmesh;

enum Place {
  kObjCoordinate, kMtlKd, kPlyFloat, kPlyDouble, kOffCoordinate, kStlCoordinate, kJsonTranslate, kProbe,
  kObjIndex, kPlyIndex, kPlyCount, kOffIndex, kPlaces
};

const char* const kMtl = "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n";

std::string ply(const std::string& type, const std::string& x, const std::string& face) {
  return "ply\nformat ascii 1.0\nelement vertex 3\nproperty " + type + " x\nproperty " + type + " y\nproperty " + type +
         " z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n" + x + " 0 0\n0 1 0\n" +
         face + "\n";
}

// A mesh file read through a JSON scene that gives it a material.
std::string through_scene(const std::string& name, const std::string& text) {
  fuzz::write_file(name, text);
  return fuzz::write_file("scene.json", "{\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": "
                                        "[1, 1, 1]}}, \"objects\": [{\"file\": \"" + name + "\", \"material\": \"grey\"}]}");
}

// Whether `token` is of `pattern` and at most `longest` characters
// (radmesh's text formats read numbers of at most 100; JSON has no bound).
bool matches(const std::string& token, const std::regex& pattern, size_t longest = 100) {
  return token.size() <= longest && std::regex_match(token, pattern);
}

const std::regex kDecimal("-?([0-9]+(\\.[0-9]*)?|\\.[0-9]+)([eE][-+]?[0-9]+)?");
const std::regex kJson("-?(0|[1-9][0-9]*)(\\.[0-9]+)?([eE][-+]?[0-9]+)?");
const std::regex kWhole("-?[0-9]{1,18}");
const std::regex kUnsigned("[0-9]{1,18}");

// The x of the vertex (x, 0, 0), x != 0, of a scene read.
double vertex_x(const Scene& s) {
  for (const Vec3& v : s.vertices)
    if (v.y == 0.0 && v.z == 0.0 && v.x != 0.0) return v.x;
  fuzz::defect("no vertex (x, 0, 0) in the scene read");
}

void expect(bool ok, const std::string& token, const std::string& what) {
  if (!ok) fuzz::defect("token '" + token.substr(0, 120) + "': " + what);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  static const char kAlphabet[] = "0123456789.eE+-0123456789.e-xXpPnNaAiIfFyY,0";
  const Place place = static_cast<Place>(data[0] % kPlaces);
  std::string token;
  for (size_t i = 2; i < size && token.size() < 400; ++i) token += kAlphabet[data[i] % (sizeof kAlphabet - 1)];
  if (data[1] & 0x80) token.insert(token.empty() ? 0 : 1, std::string(4u * (data[1] & 0x7F), '0'));
  if (token.empty()) return 0;
  const double meant = std::strtod(token.c_str(), nullptr);  // what a token of the syntax means
  const bool decimal = matches(token, kDecimal) && std::isfinite(meant);
  auto near_double = [&](double got) { return std::abs(got - meant) <= 1e-12 * std::abs(meant) + DBL_MIN; };
  auto near_float = [&](double got) { return std::abs(got - meant) <= 4e-6 * std::abs(meant) + FLT_MIN; };
  auto whole = [&](const std::regex& pattern, std::initializer_list<long long> values) {
    if (!matches(token, pattern)) return false;
    const long long v = std::strtoll(token.c_str(), nullptr, 10);
    for (const long long w : values)
      if (v == w) return true;
    return false;
  };

  fuzz::write_file("scene.mtl", kMtl);
  const std::string obj_head = "mtllib scene.mtl\nusemtl grey\nv 0 0 0\n";
  try {
    switch (place) {
      case kObjCoordinate: {
        const Scene s = read_scene(fuzz::write_file("t.obj", obj_head + "v " + token + " 0 0\nv 0 1 0\nf 1 2 3\n"));
        expect(decimal, token, "outside the syntax, read by the OBJ reader");
        expect(near_double(vertex_x(s)), token, "read by the OBJ reader as another value");
        break;
      }
      case kMtlKd: {
        fuzz::write_file("scene.mtl", "newmtl grey\nKd " + token + " 0.5 0.5\nKe 1 1 1\n");
        const Scene s = read_scene(fuzz::write_file("t.obj", obj_head + "v 1 0 0\nv 0 1 0\nf 1 2 3\n"));
        expect(decimal, token, "outside the syntax, read as an MTL Kd");
        expect(s.materials.at(0).reflectance.x == meant, token, "read as another Kd");
        break;
      }
      case kPlyFloat:
      case kPlyDouble: {
        const Scene s = read_scene(through_scene("t.ply", ply(place == kPlyFloat ? "float" : "double", token, "3 0 1 2")));
        expect(decimal, token, "outside the syntax, read by the PLY reader");
        expect(near_float(vertex_x(s)), token, "read by the PLY reader as another value");
        break;
      }
      case kOffCoordinate: {
        const Scene s = read_scene(through_scene("t.off", "OFF\n3 1 0\n0 0 0\n" + token + " 0 0\n0 1 0\n3 0 1 2\n"));
        expect(decimal, token, "outside the syntax, read by the OFF reader");
        expect(near_float(vertex_x(s)), token, "read by the OFF reader as another value");
        break;
      }
      case kStlCoordinate: {
        const Scene s = read_scene(through_scene(
            "t.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex " + token +
                         " 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n"));
        expect(decimal, token, "outside the syntax, read by the STL reader");
        expect(near_float(vertex_x(s)), token, "read by the STL reader as another value");
        break;
      }
      case kJsonTranslate: {
        fuzz::write_file("t.obj", obj_head + "v 1 0 0\nv 0 1 0\nf 1 2 3\n");
        const Scene s = read_scene(fuzz::write_file(
            "scene.json", "{\"objects\": [{\"file\": \"t.obj\", \"transform\": {\"translate\": [" + token + ", 0, 0]}}]}"));
        expect(matches(token, kJson, std::string::npos) && std::isfinite(meant), token,
               "outside JSON's syntax, read as a translation");
        double least = INFINITY;
        for (const Vec3& v : s.vertices) least = std::min(least, v.x);
        expect(least == meant, token, "read as another translation");
        break;
      }
      case kProbe: {
        const auto probes = read_probes(fuzz::write_file("probes.txt", "p " + token + " 0 0 0 1 0\n"));
        expect(decimal, token, "outside the syntax, read in a probe file");
        expect(probes.at(0).point.x == meant, token, "read in a probe file as another value");
        break;
      }
      case kObjIndex: {
        read_scene(fuzz::write_file("t.obj", obj_head + "v 1 0 0\nv 0 1 0\nf 1 2 " + token + "\n"));
        expect(whole(kWhole, {3, -1}), token, "read as an OBJ face index other than 3 or -1");
        break;
      }
      case kPlyIndex:
        read_scene(through_scene("t.ply", ply("float", "1", "3 0 1 " + token)));
        expect(whole(kWhole, {2}), token, "read as a PLY face index other than 2");
        break;
      case kPlyCount:
        read_scene(through_scene("t.ply", ply("float", "1", token + " 0 1 2")));
        expect(whole(kUnsigned, {3}), token, "read as a PLY list count other than 3");
        break;
      case kOffIndex:
        read_scene(through_scene("t.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 " + token + "\n"));
        expect(whole(kUnsigned, {2}), token, "read as an OFF face index other than 2");
        break;
      case kPlaces:
        break;
    }
  } catch (const Error&) {
  }
  return 0;
}
