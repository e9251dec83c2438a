// Small helpers several test files share.
#pragma once

#include "meshing/mesh.h"
#include "meshing/scene.h"

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
