// Small helpers several test files share.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <exception>

#include <string>
#include <vector>

namespace radmesh::test {

// A material made in code (no file): its name, reflectance and emission.
inline Material material(const std::string& name, const Rgb& reflectance, const Rgb& emission = Rgb(0.0)) {
  Material m;
  m.name = name;
  m.reflectance = reflectance;
  m.emission = emission;
  return m;
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

// Runs f, expects it to throw E, returns the message (a test failure when it
// throws nothing or something else).
template <class E, class F>
std::string message_of(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

// What an error said: its message and the options it names (Error::options).
struct Thrown {
  std::string message;
  std::vector<std::string> options;
  bool names(const std::string& option) const {
    return std::find(options.begin(), options.end(), option) != options.end();
  }
};

// Runs f, expects it to throw E (a radmesh error), returns what it said (a
// test failure when it throws nothing or something else).
template <class E, class F>
Thrown thrown(F f) {
  try {
    f();
  } catch (const E& e) {
    return {e.what(), e.options()};
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

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
