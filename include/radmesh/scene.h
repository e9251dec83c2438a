// The scene model: planar polygonal patches with a diffuse material each.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/options.h"

#include <string>
#include <utility>
#include <vector>

namespace radmesh {

struct Material {
  std::string name;
  Rgb reflectance{0.0};  // rho per channel, each in [0, 1)
  Rgb emission{0.0};     // radiant exitance E per channel, >= 0 (W/m^2 in file units)
  std::string file;      // where it was defined (for messages)
  int line = 0;          // line of its definition (newmtl)
  int reflectance_line = 0;  // line of Kd, when known
  int emission_line = 0;     // line of Ke, when known
};

// A planar polygon, possibly with holes. Loops index Scene::vertices.
struct Patch {
  std::string name;      // the OBJ o/g name
  int material = -1;     // index into Scene::materials
  std::vector<int> outer;               // counter-clockwise around `normal`
  std::vector<std::vector<int>> holes;  // each clockwise around `normal`
  Vec3 normal{0.0};      // unit normal (filled by prepare_scene)
  std::string file;      // source position of the face (for messages)
  int line = 0;
};

// One input face as read from a file, before welding and validation.
struct RawFace {
  std::string name;
  int material = -1;
  std::vector<Vec3> points;
  std::vector<std::vector<Vec3>> holes;
  std::string file;
  int line = 0;
};

struct SceneReport {
  int faces_read = 0;
  int vertices_read = 0;
  int vertices_welded = 0;        // vertices merged into an earlier coincident one
  int zero_area_faces_dropped = 0;
  int nonplanar_faces_split = 0;  // faces split into triangles
  int faces_cut_out = 0;          // faces cut out of a face of their plane they lie in (src/scene/overlap.h)
  std::vector<std::string> warnings;
};

struct Scene {
  std::string source;             // file the scene came from
  std::vector<Vec3> vertices;     // welded
  std::vector<Material> materials;
  std::vector<Patch> patches;
  SceneReport report;
  // Patch pairs (p < q, sorted) that lie in one plane facing the same way
  // with meeting boxes, whose overlap the mesh's triangles decide
  // (src/scene/overlap.h; filled by build_scene).
  std::vector<std::pair<int, int>> coplanar_pairs;

  std::vector<Vec3> loop_points(const std::vector<int>& loop) const;
  const Material& material_of(int patch) const;      // the material of patches[patch]
  const Material& material_of(const Patch& patch) const;
  double patch_area(int p) const;          // outer area minus holes
  void bounds(Vec3& lo, Vec3& hi) const;   // bounding box of all vertices
  // The scene's size: the diameter of the smallest sphere holding every
  // vertex. A box-shaped room's diagonal, and, unlike the bounding box's
  // diagonal, the same for the scene rotated (the defaults that scale
  // with the scene, such as mesh sizes, come from it).
  double diagonal() const;
  bool has_emitter() const;
};

struct SceneOptions {
  // A face is planar when every vertex lies within planarity_tolerance * (face
  // diameter) of its best-fit plane; otherwise it is split into triangles.
  double planarity_tolerance = 1e-6;
  // Vertices closer than weld_tolerance * (scene diagonal) are welded.
  double weld_tolerance = 1e-9;
  // Faces with area below area_tolerance * diameter^2 are dropped as zero-area.
  double area_tolerance = 1e-12;
  // Curved primitives (MGF sph, cyl, cone, ring, torus) are cut into planar
  // faces that lie no farther than curve_tolerance * radius from the true
  // surface (docs/scenes.md, "Curved primitives").
  double curve_tolerance = 0.01;
};

// The options of SceneOptions a user sets (the radmesh program's flags):
// curve_tolerance. build_scene checks them.
const OptionTable<SceneOptions>& scene_option_table();

// Validates raw faces and materials and builds a Scene: checks every value
// (finite coordinates, reflectance in [0,1), emission >= 0, >= 3 distinct
// vertices, a material for every face), welds coincident vertices, splits
// non-planar faces into triangles (with a warning naming the face), drops
// zero-area faces (counted). Throws InputError naming file:line and the value.
Scene build_scene(const std::vector<RawFace>& faces, std::vector<Material> materials,
                  const std::string& source, const SceneOptions& options = {});

}  // namespace radmesh
