// Contact lines (D0): exact positions, and a mesh that never crosses them.

#include "radmesh/obj_reader.h"
#include "radmesh/vtk_writer.h"
#include "radmesh/discontinuity.h"
#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radmesh/direct.h"
#include "radmesh/error_metric.h"
#include "radmesh/solve.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

using namespace radmesh;
using radmesh::test::patch_areas;
using radmesh::test::patch_named;

namespace {
using radmesh::test::kData;

// Side of the footprint square |x| <= 0.5, |z| <= 0.5: -1 inside, +1 outside, 0 on it.
int side(const Vec3& p) {
  const double m = std::max(std::abs(p.x), std::abs(p.z));
  return m < 0.5 - 1e-12 ? -1 : (m > 0.5 + 1e-12 ? 1 : 0);
}
}  // namespace

TEST(Contacts, BoxOnFloorOutlineIsTheBoxFootprintExactly) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const int floor = patch_named(s, "floor");
  ASSERT_GE(floor, 0);
  const auto segs = contact_segments(s);
  ASSERT_EQ(segs.size(), 4u);
  std::set<std::pair<double, double>> corners;
  for (const auto& d : segs) {
    EXPECT_EQ(d.patch, floor);
    EXPECT_EQ(d.kind, 0);
    for (const Vec3& p : {d.a, d.b}) {
      EXPECT_EQ(p.y, 0.0);
      EXPECT_EQ(std::max(std::abs(p.x), std::abs(p.z)), 0.5);  // exactly on the square
      corners.insert({p.x, p.z});
    }
  }
  EXPECT_EQ(corners, (std::set<std::pair<double, double>>{{-0.5, -0.5}, {-0.5, 0.5}, {0.5, -0.5}, {0.5, 0.5}}));
}

TEST(Contacts, NoFloorTriangleCrossesTheContactLine) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const int floor = patch_named(s, "floor");
  MeshingOptions o;
  o.max_edge = 0.35;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  EXPECT_EQ(rep.contact_segments, 4);
  int crossing = 0, inside = 0;
  for (int t = 0; t < m.triangle_count(); ++t) {
    if (m.patch[static_cast<size_t>(t)] != floor) continue;
    int lo = 1, hi = -1;
    for (int v : m.triangles[static_cast<size_t>(t)]) {
      const int sd = side(m.positions[static_cast<size_t>(v)]);
      lo = std::min(lo, sd);
      hi = std::max(hi, sd);
    }
    if (lo < 0 && hi > 0) ++crossing;
    if (hi <= 0) ++inside;
  }
  EXPECT_EQ(crossing, 0);
  EXPECT_GT(inside, 0);  // the footprint is meshed (the floor keeps its area)
  // Every feature edge lies on the outline.
  ASSERT_FALSE(m.feature_edges.empty());
  for (const auto& e : m.feature_edges) {
    EXPECT_EQ(side(m.positions[static_cast<size_t>(e[0])]), 0);
    EXPECT_EQ(side(m.positions[static_cast<size_t>(e[1])]), 0);
  }
  // The floor keeps its whole area.
  double area = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t)
    if (m.patch[static_cast<size_t>(t)] == floor) area += m.area(t);
  EXPECT_NEAR(area, 16.0, 1e-12);
}

TEST(Contacts, VertexValuesAreNotAveragedAcrossTheContactLine) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  MeshingOptions o;
  o.max_edge = 0.35;
  const Mesh m = mesh_scene(s, o);
  // The mean of the elements around a vertex shows what is averaged (the
  // linear fit may extrapolate a value in deep penumbra down to zero).
  SolveOptions so;
  so.field = FieldMode::mean;
  const Solution sol = solve_matrix(s, m, so);
  // Under the box the floor gets no light at all; just outside it does.
  const int floor = patch_named(s, "floor");
  double under = 0.0, beside = 1e300;
  for (int t = 0; t < m.triangle_count(); ++t) {
    if (m.patch[static_cast<size_t>(t)] != floor) continue;
    const auto& tri = m.triangles[static_cast<size_t>(t)];
    int sd = -1;
    for (int v : tri) sd = std::max(sd, side(m.positions[static_cast<size_t>(v)]));
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.positions[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      if (side(p) != 0) continue;  // values on the outline itself
      const double b = sol.nodal.radiosity[static_cast<size_t>(sol.nodal.corners[static_cast<size_t>(t)][static_cast<size_t>(k)])].x;
      if (sd <= 0) {
        under = std::max(under, b);
      } else {
        beside = std::min(beside, b);
      }
    }
  }
  EXPECT_EQ(under, 0.0);   // the footprint side of the outline stays black
  EXPECT_GT(beside, 0.0);  // the lit side does not
}

TEST(Contacts, APiercingWallCutsTheFloorAlongTheIntersection) {
  // A floor [0,4]^2 at y = 0 facing up and a wall in the plane x = 2 from
  // y = -1 to 1 and z = 1..3, facing +x: it crosses the floor along the
  // segment x = 2, z in [1, 3].
  RawFace floor, wall;
  floor.name = "floor";
  floor.material = 0;
  floor.points = {{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}};
  wall.name = "wall";
  wall.material = 0;
  wall.points = {{2, -1, 1}, {2, -1, 3}, {2, 1, 3}, {2, 1, 1}};
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  const Scene s = build_scene({floor, wall}, {m}, "test");
  const auto segs = contact_segments(s);
  ASSERT_EQ(segs.size(), 2u);  // one on the floor, one on the wall
  for (const auto& d : segs) {
    EXPECT_EQ(d.a.x, 2.0);
    EXPECT_EQ(d.b.x, 2.0);
    EXPECT_EQ(d.a.y, 0.0);
    EXPECT_EQ(d.b.y, 0.0);
    EXPECT_EQ(std::min(d.a.z, d.b.z), 1.0);
    EXPECT_EQ(std::max(d.a.z, d.b.z), 3.0);
  }
  MeshingOptions o;
  o.max_edge = 0.5;
  const Mesh mesh = mesh_scene(s, o);
  // No triangle of either patch crosses the line x = 2, y = 0 within z in [1, 3].
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const auto& tri = mesh.triangles[static_cast<size_t>(t)];
    const bool on_floor = mesh.patch[static_cast<size_t>(t)] == 0;
    int lo = 1, hi = -1;
    bool near = true;
    for (int v : tri) {
      const Vec3& p = mesh.positions[static_cast<size_t>(v)];
      const double c = on_floor ? p.x - 2.0 : p.y;
      const int sd = c < -1e-12 ? -1 : (c > 1e-12 ? 1 : 0);
      lo = std::min(lo, sd);
      hi = std::max(hi, sd);
      near = near && p.z > 1.0 && p.z < 3.0;
    }
    if (near) {
      EXPECT_FALSE(lo < 0 && hi > 0) << "triangle " << t << " crosses the intersection";
    }
  }
}

TEST(Contacts, ModeNamesAreChecked) {
  EXPECT_EQ(parse_discontinuity_mode("off"), DiscontinuityMode::off);
  EXPECT_EQ(parse_discontinuity_mode("contacts"), DiscontinuityMode::contacts);
  EXPECT_EQ(parse_discontinuity_mode("full"), DiscontinuityMode::full);
  EXPECT_THROW(parse_discontinuity_mode("yes"), InputError);
}

TEST(Contacts, LineDatasetOpensWithItsFields) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  MeshReport rep;
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::contacts;
  mesh_scene(s, o, &rep);
  ASSERT_EQ(rep.discontinuities.size(), 4u);
  const test::TempDir dir;
  const std::string path = (dir / "lines.vtu").string();
  write_discontinuities_vtu(path, rep.discontinuities);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* g = reader->GetOutput();
  ASSERT_EQ(g->GetNumberOfCells(), 4);
  EXPECT_EQ(g->GetNumberOfPoints(), 8);
  for (vtkIdType c = 0; c < 4; ++c) EXPECT_EQ(g->GetCellType(c), VTK_LINE);
  const int floor = patch_named(s, "floor");
  for (const char* name : {"kind", "emitter", "patch_id", "other_patch"}) {
    vtkDataArray* a = g->GetCellData()->GetArray(name);
    ASSERT_NE(a, nullptr) << name;
    for (vtkIdType c = 0; c < 4; ++c) {
      const double v = a->GetTuple1(c);
      const std::string n = name;
      if (n == "kind") {
        EXPECT_EQ(v, 0.0);
      } else if (n == "emitter") {
        EXPECT_EQ(v, -1.0);
      } else if (n == "patch_id") {
        EXPECT_EQ(v, floor);
      } else {
        EXPECT_NE(v, floor);
      }
    }
  }
}

namespace {
// A floor [0, n]^2 (y = 0, facing up) with n*n open boxes of side 0.5 and
// height 0.5 standing on it, each centred in its unit cell, the whole scene
// moved by `offset`.
Scene boxes_on_floor(int n, const Vec3& offset) {
  std::vector<RawFace> faces;
  auto face = [&](const std::string& name, std::vector<Vec3> pts) {
    RawFace f;
    f.name = name;
    f.material = 0;
    for (Vec3& p : pts) p += offset;
    f.points = pts;
    faces.push_back(f);
  };
  const double N = n;
  face("floor", {{0, 0, 0}, {0, 0, N}, {N, 0, N}, {N, 0, 0}});
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x0 = i + 0.25, x1 = i + 0.75, z0 = j + 0.25, z1 = j + 0.75, h = 0.5;
      face("box", {{x0, 0, z0}, {x0, h, z0}, {x1, h, z0}, {x1, 0, z0}});  // faces -z
      face("box", {{x1, 0, z1}, {x1, h, z1}, {x0, h, z1}, {x0, 0, z1}});  // faces +z
      face("box", {{x0, 0, z1}, {x0, h, z1}, {x0, h, z0}, {x0, 0, z0}});  // faces -x
      face("box", {{x1, 0, z0}, {x1, h, z0}, {x1, h, z1}, {x1, 0, z1}});  // faces +x
      face("box", {{x0, h, z0}, {x0, h, z1}, {x1, h, z1}, {x1, h, z0}});  // top, faces +y
    }
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  return build_scene(faces, {m}, "boxes");
}
}  // namespace

TEST(ContactsStress, TwoHundredOccludersOnOneReceiver) {
  const Scene s = boxes_on_floor(14, Vec3(0.0));  // 196 boxes, 981 patches
  MeshingOptions o;
  o.max_edge = 0.5;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  EXPECT_EQ(rep.contact_segments, 4 * 196);
  double floor_area = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t)
    if (m.patch[static_cast<size_t>(t)] == 0) floor_area += m.area(t);
  EXPECT_NEAR(floor_area, 196.0, 1e-9);
  EXPECT_GE(m.feature_edges.size(), static_cast<size_t>(4 * 196));
}

TEST(ContactsStress, CoordinatesAroundAMillionWithFeaturesOfOne) {
  const Vec3 offset(1e6, 1e6, -1e6);
  const Scene s = boxes_on_floor(2, offset);
  MeshingOptions o;
  o.max_edge = 0.25;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  ASSERT_EQ(rep.contact_segments, 16);
  for (const auto& d : rep.discontinuities) {
    EXPECT_EQ(d.a.y, offset.y);  // exactly in the floor's plane
    EXPECT_EQ(d.b.y, offset.y);
  }
  // No floor triangle crosses a footprint outline.
  for (int t = 0; t < m.triangle_count(); ++t) {
    if (m.patch[static_cast<size_t>(t)] != 0) continue;
    for (int bx = 0; bx < 2; ++bx)
      for (int bz = 0; bz < 2; ++bz) {
        int lo = 1, hi = -1;
        for (int v : m.triangles[static_cast<size_t>(t)]) {
          const Vec3 p = m.positions[static_cast<size_t>(v)] - offset - Vec3(bx + 0.5, 0, bz + 0.5);
          const double d = std::max(std::abs(p.x), std::abs(p.z));
          const int sd = d < 0.25 - 1e-9 ? -1 : (d > 0.25 + 1e-9 ? 1 : 0);
          lo = std::min(lo, sd);
          hi = std::max(hi, sd);
        }
        EXPECT_FALSE(lo < 0 && hi > 0) << "triangle " << t;
      }
  }
  const Solution sol = solve_matrix(s, m, {});
  for (const Rgb& b : sol.element) EXPECT_TRUE(std::isfinite(b.x));
}

namespace {
// Triangle edges of the mesh that properly cross a discontinuity segment of
// their own patch (in the patch's plane).
int crossing_edges(const Scene& s, const Mesh& m, const std::vector<DiscontinuitySegment>& lines) {
  int count = 0;
  const double tol = 1e-10 * s.diagonal();
  for (const DiscontinuitySegment& d : lines) {
    const Vec3 n = s.patches[static_cast<size_t>(d.patch)].normal;
    const Vec3 dir = d.b - d.a;
    // Signed distance of p to the segment's line within the patch plane.
    const Vec3 side = glm::normalize(glm::cross(n, dir));
    for (int t = 0; t < m.triangle_count(); ++t) {
      if (m.patch[static_cast<size_t>(t)] != d.patch) continue;
      const auto& tri = m.triangles[static_cast<size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = m.positions[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        const Vec3 q = m.positions[static_cast<size_t>(tri[static_cast<size_t>((k + 1) % 3)])];
        const double sp = glm::dot(p - d.a, side), sq = glm::dot(q - d.a, side);
        if (!((sp > tol && sq < -tol) || (sp < -tol && sq > tol))) continue;
        // Where the edge meets the line: inside the segment (not at its ends)?
        const Vec3 x = p + (sp / (sp - sq)) * (q - p);
        const double u = glm::dot(x - d.a, dir) / glm::dot(dir, dir);
        if (u * glm::length(dir) > tol && (1.0 - u) * glm::length(dir) > tol) ++count;
      }
    }
  }
  return count;
}
}  // namespace

TEST(Shadows, BoxOnFloorPenumbraLinesMatchHandDerivedCoordinates) {
  // Light: the square |x|, |z| <= 0.1 at y = 3 facing down; box: |x|, |z| <=
  // 0.5, 0 <= y <= 1. From a light vertex (sx, 3, sz) the top edge x = 0.5
  // projects to the floor at x = sx + 1.5 (0.5 - sx): 0.7 (umbra boundary,
  // sx = 0.1) and 0.8 (outer penumbra, sx = -0.1). Every light edge is
  // parallel to a box edge, so each critical plane holds both: all lines are
  // D1. Each line runs over |z| <= 0.8 (its two light vertices' wedges and
  // the box corners' VE wedges together).
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const int floor = patch_named(s, "floor"), light = patch_named(s, "light");
  ShadowReport rep;
  const auto lines = shadow_segments(s, contact_segments(s), {}, &rep);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(rep.d2, 0);
  EXPECT_EQ(rep.d1, static_cast<int>(lines.size()));
  std::map<std::pair<int, int>, std::pair<double, std::pair<double, double>>> by_line;  // (axis, 10*c) -> length, extent
  for (const DiscontinuitySegment& d : lines) {
    EXPECT_EQ(d.patch, floor);
    EXPECT_EQ(d.emitter, light);
    EXPECT_EQ(d.kind, 1);
    EXPECT_EQ(d.a.y, 0.0);
    EXPECT_EQ(d.b.y, 0.0);
    // Constant x (axis 0) or constant z (axis 2), at +-0.7 or +-0.8; the
    // constant coordinate is the one the segment does not extend in.
    const int axis = std::abs(d.b.z - d.a.z) > std::abs(d.b.x - d.a.x) ? 0 : 2;
    const double c = axis == 0 ? d.a.x : d.a.z, c2 = axis == 0 ? d.b.x : d.b.z;
    EXPECT_NEAR(c, c2, 1e-15);
    const double k = std::round(std::abs(c) * 10.0);
    EXPECT_TRUE(k == 7.0 || k == 8.0) << c;
    EXPECT_NEAR(std::abs(c), k / 10.0, 1e-15);
    const double u0 = axis == 0 ? d.a.z : d.a.x, u1 = axis == 0 ? d.b.z : d.b.x;
    auto& entry = by_line[{axis, static_cast<int>(std::round(c * 10.0))}];
    if (entry.first == 0.0) entry.second = {1e9, -1e9};
    entry.first += std::abs(u1 - u0);
    entry.second.first = std::min({entry.second.first, u0, u1});
    entry.second.second = std::max({entry.second.second, u0, u1});
  }
  ASSERT_EQ(by_line.size(), 8u);
  for (const auto& [key, entry] : by_line) {
    EXPECT_NEAR(entry.first, 1.6, 1e-12) << "axis " << key.first << " at " << key.second / 10.0;  // no overlap
    EXPECT_NEAR(entry.second.first, -0.8, 1e-15);
    EXPECT_NEAR(entry.second.second, 0.8, 1e-15);
  }
  EXPECT_EQ(rep.back_facing_pairs_skipped, 4);  // the box's four sides face away from the light
}

TEST(Shadows, FullMeshHasNoEdgeCrossingALine) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  MeshingOptions o;
  o.max_edge = 0.35;
  o.discontinuity = DiscontinuityMode::full;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  EXPECT_EQ(rep.contact_segments, 4);
  EXPECT_GT(rep.shadow_segments, 0);
  EXPECT_EQ(rep.rounding_crossings, 0);
  EXPECT_EQ(crossing_edges(s, m, rep.discontinuities), 0);
  const int floor = patch_named(s, "floor");
  ASSERT_GE(floor, 0);
  double area = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t)
    if (m.patch[static_cast<size_t>(t)] == floor) area += m.area(t);
  EXPECT_NEAR(area, 16.0, 1e-12);
}

TEST(Shadows, CornellBoxFullMeshIsValidAndNeverCrossesALine) {
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::full;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  EXPECT_EQ(rep.contact_segments, 8);
  EXPECT_GT(rep.shadow.d2, 0);  // the blocks are turned against the light
  EXPECT_EQ(rep.shadow.emitters, 1);
  EXPECT_EQ(rep.rounding_crossings, 0);
  EXPECT_EQ(crossing_edges(s, m, rep.discontinuities), 0);
  for (const DiscontinuitySegment& d : rep.discontinuities)
    if (d.kind > 0) {
      EXPECT_EQ(s.patches[static_cast<size_t>(d.emitter)].name, "light");
      EXPECT_NE(d.patch, d.emitter);
    }
  const std::vector<double> area = patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9 * s.patch_area(static_cast<int>(p)));
}

namespace {
// Scenes for the stress cases: a white floor [0, 4]^2 (y = 0, facing up)
// lit by a square light of side `light` centred above (2, h, 2), facing down,
// plus whatever `extra` adds (material 0 = white, 1 = light).
struct Builder {
  std::vector<RawFace> faces;
  void quad(const std::string& name, int material, std::vector<Vec3> pts, const Vec3& offset = Vec3(0.0)) {
    RawFace f;
    f.name = name;
    f.material = material;
    for (Vec3& p : pts) p += offset;
    f.points = pts;
    f.line = static_cast<int>(faces.size()) + 1;
    f.file = "stress";
    faces.push_back(f);
  }
  // Axis-aligned box [lo, hi] without a bottom; faces point outwards.
  void box(const Vec3& lo, const Vec3& hi) {
    quad("box", 0, {{lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, lo.y, lo.z}});
    quad("box", 0, {{hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z}});
    quad("box", 0, {{lo.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {lo.x, hi.y, lo.z}, {lo.x, lo.y, lo.z}});
    quad("box", 0, {{hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z}});
    quad("box", 0, {{lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, hi.y, lo.z}});
  }
  // A horizontal plate at height y, facing up (towards the light).
  void plate(double x0, double z0, double x1, double z1, double y) {
    quad("plate_up", 0, {{x0, y, z0}, {x0, y, z1}, {x1, y, z1}, {x1, y, z0}});
  }
  Scene build(double light_half = 0.2, double height = 3.0, const Vec3& offset = Vec3(0.0)) {
    quad("floor", 0, {{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}}, offset);
    const double a = 2.0 - light_half, b = 2.0 + light_half;
    quad("light", 1, {{a, height, a}, {b, height, a}, {b, height, b}, {a, height, b}}, offset);
    for (auto& f : faces)
      if (f.name != "floor" && f.name != "light")
        for (Vec3& p : f.points) p += offset;
    Material white, lamp;
    white.name = "white";
    white.reflectance = Rgb(0.5);
    lamp.name = "light";
    lamp.emission = Rgb(10.0);
    return build_scene(faces, {white, lamp}, "stress");
  }
};

// Meshes with every discontinuity line and checks what a valid result must
// be: finite points, each patch's area kept, no triangle edge across a line,
// finite exact direct light at sample points. Prints the time taken.
void check_full_mesh(const Scene& s, const std::string& what, double seconds_bound = 120.0) {
  const auto t0 = std::chrono::steady_clock::now();
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::full;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[stress] %-40s %6d triangles, %4d D0 + %4d D1/D2 lines, %5d crossings, %2d rounding crossings, %.3f s\n",
              what.c_str(), m.triangle_count(), rep.contact_segments, rep.shadow_segments, rep.crossings,
              rep.rounding_crossings, secs);
  EXPECT_LT(secs, seconds_bound) << what;
  for (const Vec3& p : m.positions) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << what;
  const std::vector<double> area = patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)  // fails on a NaN triangle too
    EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9 * s.patch_area(static_cast<int>(p)) + 1e-300)
        << what << ": patch " << p;
  EXPECT_GT(rep.shadow_segments, 0) << what;  // else "no edge crosses a line" would say nothing
  EXPECT_EQ(crossing_edges(s, m, rep.discontinuities), 0) << what;
  const DirectIllumination direct(s);
  const std::vector<SurfaceSample> samples = surface_samples(s, 200);
  ASSERT_GE(samples.size(), 100u) << what;  // about 200, stratified by area
  for (const SurfaceSample& q : samples) {
    const Rgb b = direct.reflected(q.x, q.patch);
    ASSERT_TRUE(std::isfinite(b.x) && b.x >= 0.0) << what;
  }
}
}  // namespace

TEST(ShadowsStress, SurfacesOneNanometreApart) {
  // A plate 1e-9 above the floor (relative to its size 1), and a box whose
  // top is 1e-9 below a plate's underside.
  Builder b;
  b.plate(1.0, 1.0, 2.0, 2.0, 1e-9);
  b.box(Vec3(2.5, 0.0, 2.5), Vec3(3.0, 0.5, 3.0));
  b.plate(2.4, 2.4, 3.1, 3.1, 0.5 + 1e-9);
  check_full_mesh(b.build(), "surfaces 1e-9 apart");
}

TEST(ShadowsStress, OccluderEdgesParallelToEmitterEdges) {
  Builder b;
  b.plate(1.5, 1.5, 2.5, 2.5, 1.0);  // every edge parallel to a light edge
  b.box(Vec3(0.5, 0.0, 0.5), Vec3(1.0, 0.7, 1.0));
  check_full_mesh(b.build(), "edges parallel to the emitter's");
}

TEST(ShadowsStress, OccluderCoplanarWithTheReceiver) {
  Builder b;
  b.quad("mat", 0, {{1, 0, 1}, {1, 0, 2}, {2, 0, 2}, {2, 0, 1}});  // lies in the floor
  b.box(Vec3(2.5, 0.0, 1.0), Vec3(3.0, 0.5, 1.5));
  check_full_mesh(b.build(), "occluder coplanar with the receiver");
}

TEST(ShadowsStress, EmitterLyingInTheCeilingItBelongsTo) {
  Builder b;
  b.quad("ceiling", 0, {{0, 3, 0}, {4, 3, 0}, {4, 3, 4}, {0, 3, 4}});  // faces down, overlaps the light
  b.box(Vec3(1.5, 0.0, 1.5), Vec3(2.2, 1.0, 2.2));
  check_full_mesh(b.build(), "emitter lying in its ceiling");
}

TEST(ShadowsStress, TinyOccluder) {
  Builder b;
  b.box(Vec3(2.0, 0.5, 2.0), Vec3(2.0 + 1e-6, 0.5 + 1e-6, 2.0 + 1e-6));
  b.box(Vec3(1.0, 0.0, 1.0), Vec3(1.0 + 1e-5, 1e-5, 1.0 + 1e-5));
  check_full_mesh(b.build(), "tiny occluders (1e-6, 1e-5)");
}

TEST(ShadowsStress, TwoHundredOccludersAboveOneReceiver) {
  Builder b;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 10; ++j) {
      const double x = 0.1 + 0.19 * i, z = 0.1 + 0.38 * j;
      b.plate(x, z, x + 0.08, z + 0.2, 1.0 + 0.01 * ((i + j) % 5));
    }
  check_full_mesh(b.build(), "200 occluders above one receiver");
}

TEST(ShadowsStress, CoordinatesAroundAMillionWithFeaturesOfOne) {
  Builder b;
  b.box(Vec3(1.5, 0.0, 1.5), Vec3(2.5, 1.0, 2.5));
  b.plate(0.5, 0.5, 1.0, 1.0, 1.5);
  check_full_mesh(b.build(0.2, 3.0, Vec3(1e6, 1e6, -1e6)), "coordinates around 1e6");
}

TEST(Shadows, ManyBoxesLinesNeitherRunAlongAContactNorRepeatAnEarlierLine) {
  // 8 x 8 boxes on the floor: 256 contact segments there, so each new line
  // is checked against the kept ones through several blocks of their search
  // structure. Every line kept on a patch must be free of collinear overlap
  // with the contacts and the lines kept before it, and no near duplicate of
  // one of them (checked here against all of them, pair by pair).
  Builder b;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      const double x = 0.3 + 0.45 * i, z = 0.3 + 0.45 * j;
      b.box(Vec3(x, 0.0, z), Vec3(x + 0.2, 0.1 + 0.05 * ((i + 2 * j) % 4), z + 0.2));
    }
  const Scene s = b.build(0.4);
  const std::vector<DiscontinuitySegment> contacts = contact_segments(s);
  ASSERT_EQ(contacts.size(), 256u);  // the boxes' footprints on the floor
  ShadowOptions o;
  o.min_separation = 2e-3;
  o.max_lines_per_receiver = 1000000;
  ShadowReport rep;
  const std::vector<DiscontinuitySegment> lines = shadow_segments(s, contacts, o, &rep);
  ASSERT_GT(lines.size(), 300u);
  EXPECT_GT(rep.near_duplicates_dropped, 0);  // else the rule below says nothing
  const double eps = 1e-9 * s.diagonal(), tol = o.min_separation;
  std::vector<std::vector<const DiscontinuitySegment*>> before(s.patches.size());
  for (const DiscontinuitySegment& c : contacts) before[static_cast<size_t>(c.patch)].push_back(&c);
  int overlaps = 0, duplicates = 0;
  for (const DiscontinuitySegment& l : lines) {
    const Vec3 ab = l.b - l.a, mid = 0.5 * (l.a + l.b);
    const double len = glm::length(ab);
    for (const DiscontinuitySegment* k : before[static_cast<size_t>(l.patch)]) {
      auto off_line = [&](const Vec3& p) { return glm::length(glm::cross(p - l.a, ab)) / len > eps; };
      if (!off_line(k->a) && !off_line(k->b)) {
        double t0 = glm::dot(k->a - l.a, ab) / (len * len), t1 = glm::dot(k->b - l.a, ab) / (len * len);
        if (t0 > t1) std::swap(t0, t1);
        if ((std::min(t1, 1.0) - std::max(t0, 0.0)) * len > eps) ++overlaps;
      }
      if (point_segment_distance(l.a, k->a, k->b) <= tol && point_segment_distance(l.b, k->a, k->b) <= tol &&
          point_segment_distance(mid, k->a, k->b) <= tol)
        ++duplicates;
    }
    before[static_cast<size_t>(l.patch)].push_back(&l);
  }
  EXPECT_EQ(overlaps, 0);
  EXPECT_EQ(duplicates, 0);
}

namespace {
// Meshes with full discontinuity lines and checks the mesh covers every
// patch exactly (triangle areas sum to the patch area) with no degenerate
// triangle outside the zero-area test.
void expect_full_mesh_covers(const Scene& s, double max_edge, const std::string& what) {
  MeshingOptions mo;
  mo.max_edge = max_edge;
  mo.discontinuity = DiscontinuityMode::full;
  MeshReport report;
  const Mesh m = mesh_scene(s, mo, &report);
  EXPECT_GT(report.shadow_segments, 0) << what;
  const std::vector<double> area = patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_NEAR(area[p] / s.patch_area(static_cast<int>(p)), 1.0, 1e-9) << what << ", patch " << s.patches[p].name;
  for (int t = 0; t < m.triangle_count(); ++t) EXPECT_GT(m.area(t), 0.0) << what << ", triangle " << t;
}
}  // namespace

TEST(DiscontinuityRegression, LineEndRoundedOffAnotherLineDoesNotCrashTheMesher) {
  // Two emitting materials in the Cornell box (white and red walls emit):
  // a shadow line ends on another line in exact arithmetic, 1e-15 off it
  // after rounding, and CGAL's mesher split the line towards that end until
  // it crashed (SIGSEGV in Delaunay_mesher_2). Now such an end is chained
  // into the line.
  Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  for (Material& m : s.materials)
    if (m.name == "white" || m.name == "red") m.emission = Rgb(1.0);
  for (double edge : {40.0, 80.0, 300.0}) expect_full_mesh_covers(s, edge, "two emitters, max edge " + std::to_string(edge));
}

TEST(DiscontinuityRegression, FloorVertexOutOfPlaneDoesNotCrashTheMesher) {
  // One floor corner moved 300 mm up: the floor is split into two
  // triangles and the same rounded line end crashed the mesher at every
  // --max-edge.
  const Scene base = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Scene s = test::transformed(base, [](const Vec3& v) {
    return v == Vec3(552.8, 0.0, 0.0) ? Vec3(552.8, 300.0, 0.0) : v;
  });
  for (double edge : {40.0, 80.0, 300.0}) expect_full_mesh_covers(s, edge, "moved vertex, max edge " + std::to_string(edge));
}

TEST(DiscontinuityRegression, NearCoincidentShadowLinesStopAtTheElementBoundNotMinutesLater) {
  // The box with white and red emitting too, and one ceiling corner 1 mm
  // below the ceiling (found by fuzz_mesh): the ceiling splits into tilted
  // triangles whose shadow lines run a millimetre apart, and the mesher
  // made 685,000 elements where the box with the same lights makes 42,694
  // (8 s against 1 s in Release). Past 15 x the points its size and edges
  // ask for, the ceiling is left as the triangulation of its outline and
  // lines, and said.
  const std::string src = kData + "/cornell_box/cornell_box";
  const test::TempDir dir;
  Scene base = read_obj_scene(src + ".obj");
  Scene s = read_obj_scene(test::write_edited_obj(src, dir.path(), [](const std::string& line, int) {
    return line == "v 0 548.8 332" ? std::string("v 0 547.8 332") : line;
  }));
  for (Scene* scene : {&base, &s})
    for (Material& m : scene->materials)
      if (m.name == "white" || m.name == "red") m.emission = Rgb(1.0);
  MeshingOptions o;
  o.max_elements = 1e5;
  MeshReport report;
  EXPECT_LE(mesh_scene(s, o, &report).triangle_count(), 100000);
  EXPECT_GE(report.thin_faces_unrefined, 1);
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_TRUE(test::mentions(report.warnings[0], {"face 'ceiling'", "--max-edge", "made more than"}));
  // Cut as finely as CGAL cuts it (the matrix method's meshing): one
  // ceiling face has a line piece 2e-4 long (under 1e-6 of the scene's
  // size) and is left unrefined all the same (CGAL's mesher is not
  // reliable around such pieces); the rest fits the bound.
  o.refine_narrow_strips = true;
  MeshReport strips;
  EXPECT_LE(mesh_scene(s, o, &strips).triangle_count(), 100000);
  ASSERT_EQ(strips.warnings.size(), 1u);
  EXPECT_TRUE(test::mentions(strips.warnings[0], {"face 'ceiling'", "discontinuity line", "under 1e-06"}));
  // The box with the same lights fits the same bound, and not one of
  // 30,000 elements: refused at the face that passes it, with the bound.
  EXPECT_LE(mesh_scene(base, o).triangle_count(), 100000);
  o.max_elements = 3e4;
  const test::Thrown t = test::thrown<GeometryError>([&] { mesh_scene(base, o); });
  EXPECT_TRUE(t.says({"face '", "30000 elements"}));
}

TEST(Contacts, ARugAMillimetreAboveTheFloorCutsItAlongItsOutline) {
  // A rug [-1, 1]^2 1 mm above a floor: nearer than the separation floor
  // (2% of --max-edge 0.5), so its outline, projected, is a contact line of
  // the floor (length 8); an element across it sent what its lit part
  // gathered into the rug's back. At 1 cm it is not.
  const Scene s = test::room_with_panel(0.001, 1.0);
  const int floor = patch_named(s, "floor"), rug = patch_named(s, "panel");
  const auto lines = overhang_segments(s, 0.01);
  ASSERT_EQ(lines.size(), 4u);
  double length = 0.0;
  for (const auto& d : lines) {
    EXPECT_EQ(d.patch, floor);
    EXPECT_EQ(d.other, rug);
    EXPECT_EQ(d.a.y, 0.0);
    EXPECT_EQ(d.b.y, 0.0);
    length += glm::length(d.b - d.a);
  }
  EXPECT_NEAR(length, 8.0, 1e-12);
  EXPECT_TRUE(overhang_segments(s, 0.0009).empty());
  EXPECT_TRUE(overhang_segments(test::room_with_panel(0.01, 1.0), 0.01).size() == 4u);
  EXPECT_TRUE(overhang_segments(test::room_with_panel(0.0101, 1.0), 0.01).empty());
  // A steep face as near (a strip standing 1 mm above the floor, 4 mm
  // tall) covers nothing: no line.
  RawFace strip;
  strip.name = "strip";
  strip.material = 1;
  strip.points = {{-1, 0.001, 0}, {1, 0.001, 0}, {1, 0.005, 0}, {-1, 0.005, 0}};
  EXPECT_TRUE(overhang_segments(test::room_with({strip}), 0.01).empty());

  MeshingOptions o;
  o.max_edge = 0.5;
  o.discontinuity = DiscontinuityMode::contacts;
  MeshReport rep;
  const Mesh m = mesh_scene(s, o, &rep);
  EXPECT_EQ(rep.contact_segments, 4);
  EXPECT_EQ(crossing_edges(s, m, rep.discontinuities), 0);
  ASSERT_FALSE(m.feature_edges.empty());
  for (const auto& e : m.feature_edges)
    for (int v : e) EXPECT_EQ(std::max(std::abs(m.positions[static_cast<size_t>(v)].x), std::abs(m.positions[static_cast<size_t>(v)].z)), 1.0);
}
