// The scene model: raw faces and materials checked value by value, welded,
// split where not planar, without zero-area faces (dropped, counted) or
// coincident ones (refused), coplanar overlaps cut out; and what a scene
// answers (areas, bounds, materials).

#include "radmesh/scene.h"

#include "core/box_tree.h"
#include "scene/overlap.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <tuple>
#include <unordered_map>

namespace radmesh {

const Material& Scene::material_of(int patch) const {
  return materials[static_cast<size_t>(patches[static_cast<size_t>(patch)].material)];
}

const Material& Scene::material_of(const Patch& patch) const { return materials[static_cast<size_t>(patch.material)]; }

std::vector<Vec3> Scene::loop_points(const std::vector<int>& loop) const {
  std::vector<Vec3> pts;
  pts.reserve(loop.size());
  for (int v : loop) pts.push_back(vertices[static_cast<size_t>(v)]);
  return pts;
}

double Scene::patch_area(int p) const {
  const Patch& patch = patches[static_cast<size_t>(p)];
  double a = 0.5 * glm::length(newell_normal(loop_points(patch.outer)));
  for (const auto& h : patch.holes) a -= 0.5 * glm::length(newell_normal(loop_points(h)));
  return a;
}

void Scene::bounds(Vec3& lo, Vec3& hi) const {
  lo = Vec3(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (const Vec3& v : vertices) {
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
}

bool Scene::has_emitter() const {
  for (const Patch& p : patches) {
    const Rgb& e = materials[static_cast<size_t>(p.material)].emission;
    if (e.x > 0.0 || e.y > 0.0 || e.z > 0.0) return true;
  }
  return false;
}

namespace {

std::string fmt(const Vec3& v) { return format_number(v.x) + " " + format_number(v.y) + " " + format_number(v.z); }

// Coordinates beyond this are refused: distances to the fourth power stay
// far inside double range.
constexpr double kMaxCoordinate = 1e50;

// Emission beyond this is refused: radiosity (up to 1000 x the emission
// where reflectance nears 1), power (times areas up to 1e100) and the sums
// over the scene stay inside double range (Ke 1e308 would give null
// energies in the summary and a radiosity of 1e308 where 2e308 is due).
constexpr double kMaxEmission = 1e50;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void check_material(const Material& m) {
  auto at = [&](int line) {
    return where(m.file, line > 0 ? line : m.line) + "material '" + m.name + "': ";
  };
  for (int c = 0; c < 3; ++c) {
    const double r = m.reflectance[c];
    if (!std::isfinite(r) || r < 0.0 || r >= 1.0)
      throw InputError(at(m.reflectance_line) + "reflectance (Kd) " + fmt(m.reflectance) +
                       " is outside [0, 1) (a reflectance of 1 or more makes the system singular)");
    const double e = m.emission[c];
    if (!std::isfinite(e) || e < 0.0 || e > kMaxEmission)
      throw InputError(at(m.emission_line) + "emission (Ke) " + fmt(m.emission) + " must be finite, >= 0 and at most " +
                       format_number(kMaxEmission));
    // A subnormal number keeps only some of its digits (5e-324 none but
    // one), and the light it gives is no longer what the file says.
    if (e > 0.0 && e < std::numeric_limits<double>::min())
      throw InputError(at(m.emission_line) + "emission (Ke) " + fmt(m.emission) + " is below " +
                       format_number(std::numeric_limits<double>::min()) +
                       ", the smallest number carried at full precision: give 0 or at least that");
  }
}

// Finds two edges of a planar face's loops (outer first, then holes; vertex
// ids into `vertices`) that cross: a proper crossing, or a collinear overlap
// along a length. Edges meeting at a shared vertex, and a vertex touching
// another edge, are not crossings. Orientations within a relative 1e-12 of
// zero count as touching. Edges are swept in order of their smallest u
// coordinate in the face's plane, so a face of many vertices costs about
// n log n. Returns an empty string when the loops are simple and disjoint,
// else which loops cross and where.
std::string find_loop_crossing(const std::vector<std::vector<int>>& loops, const std::vector<Vec3>& vertices,
                               const Vec3& n) {
  const Vec3 helper = std::abs(n.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  const Vec3 u = glm::normalize(glm::cross(n, helper)), v = glm::cross(n, u);
  struct Edge {
    int loop, a, b;
    double ua, va, ub, vb;
  };
  std::vector<Edge> edges;
  for (size_t l = 0; l < loops.size(); ++l) {
    const std::vector<int>& loop = loops[l];
    for (size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      const Vec3 &pa = vertices[static_cast<size_t>(a)], &pb = vertices[static_cast<size_t>(b)];
      edges.push_back({static_cast<int>(l), a, b, glm::dot(pa, u), glm::dot(pa, v), glm::dot(pb, u), glm::dot(pb, v)});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const Edge& x, const Edge& y) { return std::min(x.ua, x.ub) < std::min(y.ua, y.ub); });
  // Orientation of r about the line p->q: +1, -1, or 0 within rounding.
  auto orient = [](double pu, double pv, double qu, double qv, double ru, double rv) {
    const double du = qu - pu, dv = qv - pv, eu = ru - pu, ev = rv - pv;
    const double o = du * ev - dv * eu;
    const double tol = 1e-12 * std::sqrt((du * du + dv * dv) * (eu * eu + ev * ev));
    return o > tol ? 1 : (o < -tol ? -1 : 0);
  };
  auto describe = [&](const Edge& e) {
    const std::string what = e.loop == 0 ? "outline" : "hole " + std::to_string(e.loop);
    return "the " + what + " edge " + fmt(vertices[static_cast<size_t>(e.a)]) + " -> " +
           fmt(vertices[static_cast<size_t>(e.b)]);
  };
  for (size_t i = 0; i < edges.size(); ++i) {
    const Edge& e = edges[i];
    const double e_hi = std::max(e.ua, e.ub);
    for (size_t j = i + 1; j < edges.size() && std::min(edges[j].ua, edges[j].ub) <= e_hi; ++j) {
      const Edge& f = edges[j];
      if (e.a == f.a || e.a == f.b || e.b == f.a || e.b == f.b) continue;
      if (std::max(f.va, f.vb) < std::min(e.va, e.vb) || std::max(e.va, e.vb) < std::min(f.va, f.vb)) continue;
      const int o1 = orient(e.ua, e.va, e.ub, e.vb, f.ua, f.va), o2 = orient(e.ua, e.va, e.ub, e.vb, f.ub, f.vb);
      const int o3 = orient(f.ua, f.va, f.ub, f.vb, e.ua, e.va), o4 = orient(f.ua, f.va, f.ub, f.vb, e.ub, e.vb);
      bool crossing = o1 * o2 < 0 && o3 * o4 < 0;
      if (!crossing && o1 == 0 && o2 == 0) {
        // Collinear: crossing when they overlap along a length.
        const double du = e.ub - e.ua, dv = e.vb - e.va, len2 = du * du + dv * dv;
        const double t1 = ((f.ua - e.ua) * du + (f.va - e.va) * dv) / len2;
        const double t2 = ((f.ub - e.ua) * du + (f.vb - e.va) * dv) / len2;
        crossing = std::min(std::max(t1, t2), 1.0) - std::max(std::min(t1, t2), 0.0) > 1e-9;
      }
      if (crossing) return describe(e) + " crosses " + describe(f);
    }
  }
  return {};
}

// Welds points closer than eps with a uniform hash grid of cell size eps: a
// point takes the first earlier vertex within eps, scanning the 27 cells
// around it in a fixed order and each cell in insertion order. Kept vertices
// are more than eps apart, so a point equal to one of them can weld to no
// other: that common case is one look-up in a map of exact positions.
class Welder {
public:
  explicit Welder(double eps) : eps_(eps > 0.0 ? eps : std::numeric_limits<double>::min()) {}

  double tolerance() const { return eps_; }

  void reserve(size_t n) {
    exact_.reserve(n);
    grid_.reserve(n);
    next_.reserve(n);
  }

  int add(const Vec3& p, std::vector<Vec3>& out, bool* welded) {
    const auto same = exact_.find(p);
    if (same != exact_.end()) {
      *welded = true;
      return same->second;
    }
    const long long cx = cell(p.x), cy = cell(p.y), cz = cell(p.z);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          auto it = grid_.find(key(cx + dx, cy + dy, cz + dz));
          if (it == grid_.end()) continue;
          for (int id = it->second.first; id >= 0; id = next_[static_cast<size_t>(id)])
            if (glm::length(out[static_cast<size_t>(id)] - p) <= eps_) {
              *welded = true;
              return id;
            }
        }
    const int id = static_cast<int>(out.size());
    out.push_back(p);
    next_.push_back(-1);
    exact_.emplace(p, id);
    auto [it, fresh] = grid_.try_emplace(key(cx, cy, cz), id, id);
    if (!fresh) {  // append: the cell's list stays in insertion order
      next_[static_cast<size_t>(it->second.second)] = id;
      it->second.second = id;
    }
    *welded = false;
    return id;
  }

private:
  struct ExactHash {
    size_t operator()(const Vec3& v) const {
      const std::hash<double> h;
      return h(v.x) ^ (h(v.y) * 0x9E3779B97F4A7C15ULL) ^ (h(v.z) * 0xC2B2AE3D27D4EB4FULL);
    }
  };
  // Clamped into long long: far cells may share a key (the exact distance
  // test still decides), never an overflowing conversion.
  long long cell(double x) const { return static_cast<long long>(std::clamp(std::floor(x / eps_), -9e18, 9e18)); }
  static uint64_t key(long long x, long long y, long long z) {
    return (static_cast<uint64_t>(x) * 73856093ULL) ^ (static_cast<uint64_t>(y) * 19349663ULL) ^
           (static_cast<uint64_t>(z) * 83492791ULL);
  }
  double eps_;
  std::unordered_map<Vec3, int, ExactHash> exact_;                // kept vertex at exactly this position
  std::unordered_map<uint64_t, std::pair<int, int>> grid_;  // cell -> first and last vertex in it
  std::vector<int> next_;                                          // next vertex in the same cell, or -1
};

// The largest distance between two points: exact for up to 64 points, else
// the bounding box's diagonal (at most sqrt(3) times it), so that a face of a
// million vertices costs a million steps, not 1e12.
double diameter(const std::vector<Vec3>& pts) {
  double d = 0.0;
  if (pts.size() <= 64) {
    for (size_t i = 0; i < pts.size(); ++i)
      for (size_t j = i + 1; j < pts.size(); ++j) d = std::max(d, glm::length(pts[i] - pts[j]));
    return d;
  }
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return glm::length(hi - lo);
}

// How far the points reach off the line through the first point and the one
// farthest from it: 0 when they all lie on one line.
double off_line(const std::vector<Vec3>& pts) {
  size_t far = 0;
  for (size_t i = 1; i < pts.size(); ++i)
    if (glm::length(pts[i] - pts[0]) > glm::length(pts[far] - pts[0])) far = i;
  const Vec3 d = pts[far] - pts[0];
  const double len = glm::length(d);
  if (len == 0.0) return 0.0;
  double off = 0.0;
  for (const Vec3& p : pts) off = std::max(off, glm::length(glm::cross(p - pts[0], d)) / len);
  return off;
}

// Removes consecutive repeated indices (cyclically).
std::vector<int> dedupe_loop(std::vector<int> loop) {
  std::vector<int> out;
  for (int v : loop)
    if (out.empty() || out.back() != v) out.push_back(v);
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

// Every coordinate finite, every face with a material; counts the faces and
// vertices read. Returns the scene's size (its bounding box's diagonal, for
// tolerances; 0 without faces).
double check_faces(const std::vector<RawFace>& faces, Scene& scene) {
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const RawFace& f : faces) {
    auto at = [&f] { return where(f.file, f.line) + "face '" + f.name + "': "; };
    if (f.material < 0 || f.material >= static_cast<int>(scene.materials.size()))
      throw InputError(at() + "has no material (use usemtl with a material from the MTL file)");
    auto check = [&](const std::vector<Vec3>& loop) {
      for (const Vec3& p : loop) {
        if (!finite(p)) throw InputError(at() + "coordinate " + fmt(p) + " is not finite");
        if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxCoordinate)
          throw InputError(at() + "coordinate " + fmt(p) + " is beyond +-" + format_number(kMaxCoordinate) +
                           " (form factors take the fourth power of distances, which would overflow); "
                           "use a smaller unit");
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
    };
    check(f.points);
    for (const auto& h : f.holes) check(h);
    ++scene.report.faces_read;
    scene.report.vertices_read += static_cast<int>(f.points.size());
  }
  return faces.empty() ? 0.0 : glm::length(hi - lo);
}

// How many distinct points, and distinct vertex ids, a loop has.
int distinct_points(std::vector<Vec3> points) {
  const auto less = [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
  std::sort(points.begin(), points.end(), less);
  return static_cast<int>(std::unique(points.begin(), points.end()) - points.begin());
}
int distinct(std::vector<int> loop) {
  std::sort(loop.begin(), loop.end());
  return static_cast<int>(std::unique(loop.begin(), loop.end()) - loop.begin());
}

// Makes the scene's patches from its faces: welds their vertices, drops
// zero-area faces (counted, and said for the first 5), splits non-planar
// ones into triangles and refuses faces that are not simple polygons.
// Records per patch the centroid of its face's points as given, before
// welding (for the check of coincident patches).
class PatchMaker {
public:
  PatchMaker(Scene& scene, const SceneOptions& options, double diag)
      : scene_(scene), options_(options), welder_(options.weld_tolerance * diag) {
    welder_.reserve(static_cast<size_t>(scene.report.vertices_read));
    weld_text_ = "the weld tolerance " + format_number(welder_.tolerance()) + " (of the scene size " +
                 format_number(diag) + "): dropped as zero-area";
  }

  // Per patch: the centroid of its face's points as given, before welding.
  const std::vector<Vec3>& raw_centroid() const { return raw_centroid_; }

  void add(const RawFace& f) {
    auto at = [&f] { return where(f.file, f.line) + "face '" + f.name + "': "; };
    Vec3 given(0.0);
    for (const Vec3& p : f.points) given += p / static_cast<double>(f.points.size());
    auto [slot, fresh] = objects_.try_emplace(f.name, object_order_.size());
    if (fresh) {
      object_order_.push_back({f.name, ObjectFaces{}});
      object_order_.back().second.file = f.file;
      object_order_.back().second.line = f.line;
    }
    ObjectFaces& object = object_order_[slot->second].second;
    for (const Vec3& p : f.points) object.extent.add(p);
    const size_t patches_before = scene_.patches.size();
    // Dropped, counted, and said for the first 5.
    auto drop_as_zero_area = [&](const std::string& why) {
      if (++scene_.report.zero_area_faces_dropped <= 5)
        scene_.report.warnings.push_back(where(f.file, f.line) + "face '" + f.name + "' " + why);
    };
    std::vector<int> outer = weld_loop(f.points);
    const int kept = distinct(outer);
    if (kept < 3 && distinct_points(f.points) >= 3) {
      // Distinct as given, welded into fewer than 3: thinner than the weld
      // tolerance, a zero-area face at the scene's resolution.
      drop_as_zero_area("has its vertices welded into " + std::to_string(kept) + " within " + weld_text_);
      ++object.welded;
      return;
    }
    if (kept < 3) {
      // Far from the origin for its size, its vertices may be distinct in
      // the file and equal in double (an object moved 1e49 away).
      double far = 0.0;
      for (const Vec3& p : f.points) far = std::max(far, glm::length(p));
      const std::string hint =
          far > 1e15 * diameter(f.points)
              ? "; it lies " + format_number(far) +
                    " from the origin, where double precision (16 digits) cannot keep its vertices apart: move the "
                    "scene nearer the origin"
              : "";
      throw InputError(at() + "has " + std::to_string(kept) + " distinct vertices; a face needs at least 3" + hint);
    }
    std::vector<Vec3> pts = scene_.loop_points(outer);
    const Vec3 newell = newell_normal(pts);
    const double area = 0.5 * glm::length(newell);
    const double diam = diameter(pts);
    if (!(area > options_.area_tolerance * diam * diam)) {
      // Zero area with vertices off one line: the face's lobes cancel (a
      // symmetric bow tie), and it has no inside to drop or keep.
      if (off_line(pts) > options_.planarity_tolerance * diam)
        throw InputError(at() + "is not a simple polygon: its edges cross so that its signed area is zero, though "
                                "its vertices do not lie on one line; check the order of the face's vertices");
      drop_as_zero_area("has zero area: dropped");
      return;
    }
    // Thinner than the weld tolerance (its area over its diameter, a
    // triangle's height over its longest edge): at the scene's resolution
    // it has no inside, and meshing it found no triangle.
    if (2.0 * area / diam < welder_.tolerance()) {
      drop_as_zero_area("is " + format_number(2.0 * area / diam) + " wide, below " + weld_text_);
      ++object.welded;
      return;
    }
    const Vec3 n = newell / (2.0 * area);
    Vec3 centroid(0.0);
    for (const Vec3& p : pts) centroid += p;
    centroid /= static_cast<double>(pts.size());
    double deviation = 0.0;
    for (const Vec3& p : pts) deviation = std::max(deviation, std::abs(glm::dot(p - centroid, n)));

    Patch patch;
    patch.name = f.name;
    patch.material = f.material;
    patch.file = f.file;
    patch.line = f.line;

    if (deviation > options_.planarity_tolerance * diam) {
      if (!f.holes.empty())
        throw InputError(at() + "is not planar (deviation " + format_number(deviation) +
                         ") and has holes; split it into planar faces");
      split_into_triangles(f, patch, outer, given, deviation, diam);
      object.kept += scene_.patches.size() > patches_before ? 1 : 0;
      return;
    }

    patch.outer = std::move(outer);
    patch.normal = n;
    for (const auto& hp : f.holes) {
      std::vector<int> hole = weld_loop(hp);
      if (distinct(hole) < 3)
        throw InputError(at() + "has a hole with fewer than 3 distinct vertices");
      const std::vector<Vec3> hpts = scene_.loop_points(hole);
      for (const Vec3& p : hpts)
        if (std::abs(glm::dot(p - centroid, n)) > options_.planarity_tolerance * diam)
          throw InputError(at() + "hole vertex " + fmt(p) + " is not in the face's plane");
      if (glm::dot(newell_normal(hpts), n) > 0.0) std::reverse(hole.begin(), hole.end());
      patch.holes.push_back(std::move(hole));
    }
    // A face whose outline crosses itself (a quad with its vertices out of
    // order, a hole over the outline) has no inside: the mesher would
    // invent a vertex at each crossing, and could refine towards one
    // without end.
    std::vector<std::vector<int>> loops = {patch.outer};
    loops.insert(loops.end(), patch.holes.begin(), patch.holes.end());
    if (const std::string crossing = find_loop_crossing(loops, scene_.vertices, n); !crossing.empty())
      throw InputError(at() + "is not a simple polygon: " + crossing +
                       "; check the order of the face's vertices (radmesh needs faces whose edges do not cross)");
    scene_.patches.push_back(std::move(patch));
    raw_centroid_.push_back(given);
    ++object.kept;
  }

  // InputError for an object (faces of one name) the weld left nothing of
  // that is itself small at the scene's resolution (under 1000 weld
  // tolerances across; a long sliver is dropped as zero-area, with a
  // warning): a scene spanning far more than its objects (one moved 1e20
  // away) makes every other object a point.
  void refuse_vanished_objects(const std::string& source) const {
    for (const auto& [name, o] : object_order_) {
      const double across = glm::length(o.extent.hi - o.extent.lo);
      if (o.kept > 0 || o.welded == 0 || !(across < 1e3 * welder_.tolerance())) continue;
      throw InputError(where(o.file, o.line) + "object '" + name + "': " +
                       (o.welded == 1 ? std::string("its face is") : "all its " + std::to_string(o.welded) + " faces are") +
                       " finer than the scene's resolution: it is " + format_number(across) +
                       " across, and points closer than " + format_number(welder_.tolerance()) +
                       " (1e-9 of the scene's size) are one; the scene (" + source + ") spans " +
                       format_number(welder_.tolerance() / options_.weld_tolerance) +
                       ": bring its parts closer together, or solve them apart");
    }
  }

private:
  std::vector<int> weld_loop(const std::vector<Vec3>& pts) {
    std::vector<int> loop;
    for (const Vec3& p : pts) {
      bool welded = false;
      loop.push_back(welder_.add(p, scene_.vertices, &welded));
      if (welded) ++scene_.report.vertices_welded;
    }
    return dedupe_loop(std::move(loop));
  }

  // A non-planar face (`patch` holds its name and material) fan-split into
  // triangles; each keeps the face's name and material.
  void split_into_triangles(const RawFace& f, const Patch& patch, const std::vector<int>& outer, const Vec3& given,
                            double deviation, double diam) {
    int made = 0;
    for (size_t i = 1; i + 1 < outer.size(); ++i) {
      const std::vector<int> tri = {outer[0], outer[i], outer[i + 1]};
      const std::vector<Vec3> tp = scene_.loop_points(tri);
      const Vec3 tn = newell_normal(tp);
      const double ta = 0.5 * glm::length(tn);
      if (!(ta > options_.area_tolerance * diam * diam)) continue;
      Patch t = patch;
      t.outer = tri;
      t.normal = tn / (2.0 * ta);
      scene_.patches.push_back(std::move(t));
      raw_centroid_.push_back(given);
      ++made;
    }
    ++scene_.report.nonplanar_faces_split;
    scene_.report.warnings.push_back(where(f.file, f.line) + "face '" + f.name +
                                     "' is not planar (a vertex lies " + format_number(deviation) +
                                     " from its plane, " + format_number(deviation / diam) +
                                     " of its size): split into " + std::to_string(made) +
                                     " triangles");
  }

  Scene& scene_;
  const SceneOptions& options_;
  Welder welder_;
  std::string weld_text_;
  std::vector<Vec3> raw_centroid_;
  // Per object name: its faces kept and dropped by the weld, their extent,
  // where it starts.
  struct ObjectFaces {
    int kept = 0, welded = 0;
    Box3 extent;
    std::string file;
    int line = 0;
  };
  std::vector<std::pair<std::string, ObjectFaces>> object_order_;  // in the order of their first faces
  std::unordered_map<std::string, size_t> objects_;                  // name -> its place in object_order_
};

// Two faces on the same vertices facing the same way (a face line written
// twice) would be two coincident patches: which one is lit, and which one
// meshes, is not defined. Refused, naming both. Facing opposite ways they
// are the two sides of a thin panel, and fine, unless as given they faced
// each other across a gap that welding closed: then no light would pass
// between them, and that is refused too.
void refuse_coincident_patches(const Scene& scene, const std::vector<Vec3>& raw_centroid,
                               const SceneOptions& options, double diag) {
  // The problem with patch p lying on the same vertices as an earlier
  // patch q, or "".
  auto coincident = [&](size_t p, size_t q) -> std::string {
    const Patch& patch = scene.patches[p];
    const Patch& first = scene.patches[q];
    if (glm::dot(first.normal, patch.normal) > 0.0)
      return where(patch.file, patch.line) + "face '" + patch.name + "' lies on the same vertices as face '" +
             first.name + "' (" + where(first.file, first.line) +
             "facing the same way: two coincident faces); remove one of them";
    const Vec3 gap = raw_centroid[p] - raw_centroid[q];
    if (glm::dot(gap, first.normal) > 0.0 && glm::dot(-gap, patch.normal) > 0.0)
      return where(patch.file, patch.line) + "face '" + patch.name + "' and face '" + first.name + "' (" +
             where(first.file, first.line) + "face each other across a gap of " +
             format_number(std::abs(glm::dot(gap, first.normal))) + ", below the weld tolerance " +
             format_number(options.weld_tolerance * diag) + " (of the scene size " + format_number(diag) +
             "): welded, they would be one surface and no light would pass between them; "
             "move them further apart or remove one";
    return "";
  };
  // Patches on the same vertices lie side by side once sorted by a hash of
  // their sorted vertex lists, then by the lists (kept in one flat array,
  // cheaper than a hash map keyed by each list on a million faces). The
  // problem reported is the first patch's in file order.
  const size_t np = scene.patches.size();
  std::vector<size_t> begin(np + 1, 0);
  for (size_t p = 0; p < np; ++p) {
    begin[p + 1] = begin[p] + scene.patches[p].outer.size();
    for (const auto& h : scene.patches[p].holes) begin[p + 1] += h.size();
  }
  std::vector<int> ids(begin[np]);
  std::vector<std::pair<uint64_t, size_t>> order(np);  // (hash, patch)
  for (size_t p = 0; p < np; ++p) {
    const Patch& patch = scene.patches[p];
    auto at = ids.begin() + static_cast<std::ptrdiff_t>(begin[p]);
    auto end = std::copy(patch.outer.begin(), patch.outer.end(), at);
    for (const auto& h : patch.holes) end = std::copy(h.begin(), h.end(), end);
    std::sort(at, end);
    uint64_t hash = 1469598103934665603ULL;  // FNV-1a over the sorted list
    for (auto i = at; i != end; ++i) hash = (hash ^ static_cast<uint32_t>(*i)) * 1099511628211ULL;
    order[p] = {hash, p};
  }
  auto list = [&](size_t p, size_t end) { return ids.begin() + static_cast<std::ptrdiff_t>(begin[p + end]); };
  auto same_list = [&](size_t a, size_t b) { return std::equal(list(a, 0), list(a, 1), list(b, 0), list(b, 1)); };
  std::sort(order.begin(), order.end());
  size_t worst = np;  // the first patch, in file order, with a problem
  std::string problem;
  for (size_t k = 0, end; k < np; k = end) {
    for (end = k + 1; end < np && order[end].first == order[k].first;) ++end;
    for (size_t i = k + 1; i < end; ++i)  // patches in file order within one hash
      for (size_t j = k; j < i; ++j) {
        const size_t p = order[i].second, q = order[j].second;
        if (p > worst || !same_list(p, q)) continue;
        std::string why = coincident(p, q);
        if (!why.empty() && p < worst) {
          worst = p;
          problem = std::move(why);
        }
      }
  }
  if (worst < np) throw InputError(problem);
}

// A face lying in a larger one of its plane (a lamp in an uncut ceiling)
// is cut out of it, and said; other overlaps in one plane are refused.
void cut_out_coplanar_faces(Scene& scene, const std::string& source, const SceneOptions& options) {
  const std::vector<std::pair<int, int>> cuts = settle_coplanar_faces(scene, options.planarity_tolerance);
  scene.report.faces_cut_out = static_cast<int>(cuts.size());
  for (size_t k = 0; k < cuts.size() && k < 5; ++k) {
    const Patch& in = scene.patches[static_cast<size_t>(cuts[k].first)];
    const Patch& out = scene.patches[static_cast<size_t>(cuts[k].second)];
    scene.report.warnings.push_back(where(in.file, in.line) + "face '" + in.name + "' lies in face '" + out.name +
                                    "'" + also_at(out.file, out.line) + ", in its plane and facing the same way: cut out of it as a hole, since what "
                                    "a face covers is hidden");
  }
  if (cuts.size() > 5)
    scene.report.warnings.push_back(source + ": cut " + std::to_string(cuts.size()) +
                                    " faces in all out of the faces of their plane they lie in");
}

}  // namespace

const OptionTable<SceneOptions>& scene_option_table() {
  static const OptionTable<SceneOptions> table = [] {
    OptionTable<SceneOptions> t("scene");
    t.real("curve_tolerance", &SceneOptions::curve_tolerance, "radii",
           "how far the planar faces cut from a curved MGF primitive (sph, cyl, cone, ring, torus) may lie from "
           "its surface", 1e-5, 0.5);
    return t;
  }();
  return table;
}

Scene build_scene(const std::vector<RawFace>& faces, std::vector<Material> materials,
                  const std::string& source, const SceneOptions& options) {
  scene_option_table().check(options);
  Scene scene;
  scene.source = source;
  for (const Material& m : materials) check_material(m);
  scene.materials = std::move(materials);

  const double diag = check_faces(faces, scene);
  PatchMaker maker(scene, options, diag);
  for (const RawFace& f : faces) maker.add(f);
  maker.refuse_vanished_objects(source);
  refuse_coincident_patches(scene, maker.raw_centroid(), options, diag);
  cut_out_coplanar_faces(scene, source, options);

  if (scene.report.zero_area_faces_dropped > 5)
    scene.report.warnings.push_back(source + ": dropped " +
                                    std::to_string(scene.report.zero_area_faces_dropped) +
                                    " zero-area faces in all");
  if (scene.patches.empty()) throw InputError(source + ": the scene has no faces with area");
  if (!scene.has_emitter())
    scene.report.warnings.push_back(source +
                                    ": no face emits light (no Ke > 0): every radiosity will be "
                                    "zero and the picture black");
  return scene;
}

}  // namespace radmesh
