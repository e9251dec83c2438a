// What the test programs share: the data folder, a fresh temporary folder
// per test, checks of errors, and the scene builders.
#pragma once

#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radmesh/scene.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <map>
#include <string>
#include <system_error>
#include <vector>

namespace radmesh::test {

// ---------------------------------------------------------------- files

// The test data: the project's data/ and tests/data/bad, copied into the
// build tree (tests/CMakeLists.txt).
inline const std::string kData = RADMESH_TEST_DATA;

// A fresh, empty folder for the running test, removed with all it holds
// when the object goes. Its name is the test's (suite and name) with the
// process id, under ::testing::TempDir() (TEST_TMPDIR or TMPDIR, else
// /tmp): tests run at once (ctest -j runs each test in a process of its
// own) never share one. `tag` names a second folder of the same test; a
// folder that is there already (two of one test and tag) is left alone
// and the next free name taken (_1, _2, ...).
class TempDir {
public:
  explicit TempDir(const std::string& tag = "") {
    namespace fs = std::filesystem;
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "no_test";
    if (!tag.empty()) name += "." + tag;
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-') c = '_';
    name = "radmesh_" + name.substr(0, 160) + "_" + std::to_string(::getpid());
    const fs::path parent = ::testing::TempDir();
    fs::create_directories(parent);
    for (int n = 0;; ++n) {
      path_ = parent / (n == 0 ? name : name + "_" + std::to_string(n));
      if (fs::create_directory(path_)) break;
    }
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string string() const { return path_.string(); }
  std::filesystem::path operator/(const std::filesystem::path& part) const { return path_ / part; }

private:
  std::filesystem::path path_;
};

// ---------------------------------------------------------------- errors

// ---------------------------------------------------------------- scenes

// A material made in code (no file): its name, reflectance and emission.
inline Material material(const std::string& name, const Rgb& reflectance, const Rgb& emission = Rgb(0.0)) {
  Material m;
  m.name = name;
  m.reflectance = reflectance;
  m.emission = emission;
  return m;
}

// Appends a face named `name` of material `material` with outline `pts`.
inline void add_face(std::vector<RawFace>& faces, const std::string& name, int material, std::vector<Vec3> pts) {
  RawFace f;
  f.name = name;
  f.material = material;
  f.points = std::move(pts);
  faces.push_back(std::move(f));
}

// The six faces of the box [lo, hi] as quads named `name` with material
// `material`, facing out (a block) or in (a room).
inline std::vector<RawFace> box_faces(const std::string& name, int material, const Vec3& lo, const Vec3& hi,
                                      bool outward = true) {
  std::vector<std::vector<Vec3>> q = {
      {{lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, lo.y, lo.z}},
      {{lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}},
      {{lo.x, lo.y, lo.z}, {lo.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {lo.x, hi.y, lo.z}},
      {{hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z}},
      {{lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, hi.y, lo.z}},
      {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}}};
  std::vector<RawFace> faces;
  for (auto& pts : q) {
    RawFace f;
    f.name = name;
    f.material = material;
    f.points = std::move(pts);
    if (!outward) std::reverse(f.points.begin(), f.points.end());
    faces.push_back(std::move(f));
  }
  return faces;
}

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// Whether `text` holds every one of `parts` (a file:line, a value, a face's
// name): a failure names the first one missing and shows the text.
inline ::testing::AssertionResult mentions(const std::string& text, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts)
    if (!contains(text, part)) return ::testing::AssertionFailure() << "no \"" << part << "\" in: " << text;
  return ::testing::AssertionSuccess();
}

// The radmesh error class of e, as a name: "InputError", "GeometryError",
// "NumericalError", "IoError" (or "Error").
inline std::string error_type(const Error& e) {
  if (dynamic_cast<const InputError*>(&e)) return "InputError";
  if (dynamic_cast<const GeometryError*>(&e)) return "GeometryError";
  if (dynamic_cast<const NumericalError*>(&e)) return "NumericalError";
  if (dynamic_cast<const IoError*>(&e)) return "IoError";
  return "Error";
}

// What an error said: its class, its message and the options it names
// (Error::options, as the options structs name them).
struct Thrown {
  std::string type;
  std::string message;
  std::vector<std::string> options;
  bool names(const std::string& option) const {
    return std::find(options.begin(), options.end(), option) != options.end();
  }
  // Whether the message holds every one of `parts` (see mentions).
  ::testing::AssertionResult says(std::initializer_list<std::string> parts) const { return mentions(message, parts); }
};

// Runs f, expects it to throw E (a radmesh error: thrown<Error> takes any
// and tells which in `type`), returns what it said (a test failure when it
// throws nothing or something else).
template <class E, class F>
Thrown thrown(F f) {
  try {
    f();
  } catch (const E& e) {
    return {error_type(e), e.what(), e.options()};
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

// thrown<E>(f)'s message alone.
template <class E, class F>
std::string message_of(F f) {
  return thrown<E>(f).message;
}

// Every file under `dir` (relative name -> content); empty when there is no `dir`.
inline std::map<std::string, std::string> folder(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    out[fs::relative(e.path(), dir).string()] =
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return out;
}

// The names in a folder() listing, for a failure message.
inline std::string names(const std::map<std::string, std::string>& files) {
  std::string out;
  for (const auto& [name, content] : files) out += (out.empty() ? "" : ", ") + name;
  return "{" + out + "}";
}

// Index of the first patch named `name`, or -1.
inline int patch_named(const Scene& s, const std::string& name) {
  for (size_t p = 0; p < s.patches.size(); ++p)
    if (s.patches[p].name == name) return static_cast<int>(p);
  return -1;
}

// Sum of the mesh's triangle areas per patch.
inline std::vector<double> patch_areas(const Scene& s, const Mesh& m) {
  std::vector<double> area(s.patches.size(), 0.0);
  for (int t = 0; t < m.triangle_count(); ++t) area[static_cast<size_t>(m.patch[static_cast<size_t>(t)])] += m.area(t);
  return area;
}

// A closed room [-2, 2] x [0, 4] x [-2, 2] (material 0, white 0.7; its
// bottom face named "floor", the others "room"), a lamp 0.5 x 0.5 facing
// down at y = 3.5 (material 2, emitting 10), and `extra` (material 1 is
// grey, 0.5).
inline Scene room_with(const std::vector<RawFace>& extra) {
  std::vector<RawFace> faces = box_faces("room", 0, Vec3(-2, 0, -2), Vec3(2, 4, 2), false);
  faces[5].name = "floor";
  RawFace lamp;
  lamp.name = "lamp";
  lamp.material = 2;
  lamp.points = {{-0.25, 3.5, -0.25}, {0.25, 3.5, -0.25}, {0.25, 3.5, 0.25}, {-0.25, 3.5, 0.25}};
  faces.push_back(lamp);
  faces.insert(faces.end(), extra.begin(), extra.end());
  return build_scene(faces, {material("white", Rgb(0.7)), material("grey", Rgb(0.5)), material("lamp", Rgb(0.0), Rgb(10.0))},
                     "room");
}

// room_with a one-sided panel "panel" [-s, s]^2 (grey) at height h facing
// up: a rug just above the floor, or a table top.
inline Scene room_with_panel(double h, double s) {
  RawFace panel;
  panel.name = "panel";
  panel.material = 1;
  panel.points = {{-s, h, -s}, {-s, h, s}, {s, h, s}, {s, h, -s}};
  return room_with({panel});
}

// Writes `dir`/scene.obj from the OBJ `src` + ".obj", each line (numbered
// from 1) through `edit`, which returns the text to write in its place (one
// or more lines); copies `src` + ".mtl" beside it under its own name, so
// that the OBJ's mtllib still finds it. Returns the new OBJ's path.
inline std::string write_edited_obj(const std::string& src, const std::filesystem::path& dir,
                                    const std::function<std::string(const std::string&, int)>& edit) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  fs::copy_file(src + ".mtl", dir / fs::path(src + ".mtl").filename(), fs::copy_options::overwrite_existing);
  std::ifstream in(src + ".obj");
  std::ofstream obj(dir / "scene.obj");
  int n = 0;
  for (std::string line; std::getline(in, line);) obj << edit(line, ++n) << '\n';
  return (dir / "scene.obj").string();
}

// Rebuilds a scene from its patches (outer loops) with every point mapped by
// f, the faces in the order `order` (a permutation of the patch indices;
// empty: as they are).
template <class Map>
Scene transformed(const Scene& s, Map f, std::vector<int> order = {}) {
  if (order.empty())
    for (size_t p = 0; p < s.patches.size(); ++p) order.push_back(static_cast<int>(p));
  std::vector<RawFace> faces;
  for (int p : order) {
    const Patch& patch = s.patches[static_cast<size_t>(p)];
    RawFace face;
    face.name = patch.name;
    face.material = patch.material;
    for (const Vec3& v : s.loop_points(patch.outer)) face.points.push_back(f(v));
    faces.push_back(face);
  }
  return build_scene(faces, s.materials, "transformed");
}

}  // namespace radmesh::test
