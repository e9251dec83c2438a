// The display field: exact direct light and a final gather at every vertex.
// The evaluator's state and the source trees are field_impl.h, the
// clustered gather field_clusters.cpp.

#include "radmesh/field.h"

#include "field/field_impl.h"
#include "radmesh/errors.h"

#include <glm/matrix.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace radmesh {

using internal::SourceTree;

namespace {

// A point's gather lists what may lie between it and a source (once) where
// the source's cut has at least this many parts; see indirect().
constexpr size_t kListedParts = 8;

// The share of what the solve says a point gathers for which a part of a
// source gets the rays_per_node shadow rays, its rays in proportion to what
// it sends (FieldEvaluator::Impl::rays_for; a cluster taken whole keeps at
// least rays_per_node): against the same solve's field with 64 rays for
// every part, this share cuts per-vertex noise (95th percentile of the
// relative difference) with fewer rays than a fixed number per part. It is
// taken of the point's own value, not its patch's mean, so that dark
// vertices (under a rug) get their rays too
// (Field.BesideARugAMillimetreAboveTheFloor...).
constexpr double kRayShare = 0.005;

// Lambert's formula for a whole patch (outline less holes), front side only.
double patch_form_factor(const Vec3& x, const Vec3& n, const std::vector<std::vector<Vec3>>& loops,
                         const Vec3& normal) {
  if (glm::dot(x - loops[0][0], normal) <= 0.0) return 0.0;
  double f = std::abs(lambert_contour_sum(x, n, loops[0].data(), loops[0].size()));
  for (size_t h = 1; h < loops.size(); ++h) f -= std::abs(lambert_contour_sum(x, n, loops[h].data(), loops[h].size()));
  return std::max(0.0, f) / (2.0 * std::numbers::pi);
}

}  // namespace

FieldMode parse_field_mode(const std::string& text) {
  if (text == "auto") return FieldMode::automatic;
  if (text == "gather") return FieldMode::gather;
  if (text == "fit") return FieldMode::fit;
  if (text == "mean") return FieldMode::mean;
  throw InputError("field " + text + ": expected one of auto, gather, fit, mean", {"field"});
}

std::string to_string(FieldMode mode) {
  switch (mode) {
    case FieldMode::automatic: return "auto";
    case FieldMode::gather: return "gather";
    case FieldMode::fit: return "fit";
    case FieldMode::mean: return "mean";
    case FieldMode::own: return "own";
  }
  return "?";
}

NodalMethod nodal_method(FieldMode mode) { return mode == FieldMode::mean ? NodalMethod::mean : NodalMethod::linear_fit; }

namespace {

int emitter_count(const Scene& scene) {
  int e = 0;
  for (const Patch& p : scene.patches) e += max3(scene.material_of(p).emission) > 0.0 ? 1 : 0;
  return e;
}

// The (vertex, source) pairs a clustered gather over `vertices` vertices is
// taken for.
double clustered_pairs(double vertices, int emitters) { return vertices * (kClusterCut + emitters); }

}  // namespace

bool gather_within_budget(const Scene& scene, double vertices) {
  return gather_every_patch(vertices, static_cast<double>(scene.patches.size())) ||
         clustered_pairs(vertices, emitter_count(scene)) <= kGatherBudget;
}

FieldMode resolve_field_mode(FieldMode requested, const Scene& scene, const Mesh& mesh, std::string* why) {
  if (requested != FieldMode::automatic) return requested;
  const double vertices = static_cast<double>(mesh.positions.size());
  if (gather_within_budget(scene, vertices)) return FieldMode::gather;
  const int emitters = emitter_count(scene);
  if (why)
    *why = "field: the fit, not the gather: " + format_number(vertices) + " vertices x (" +
           format_number(kClusterCut) + " clusters or patches + " + std::to_string(emitters) +
           " emitters) = " + format_number(clustered_pairs(vertices, emitters)) +
           " (vertex, source) pairs, over the automatic gather's budget of " + format_number(kGatherBudget) +
           " (--field gather forces it)";
  return FieldMode::fit;
}

FieldEvaluator::FieldEvaluator(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                               const SolveOptions& options, GatherSources how)
    : impl_(std::make_unique<Impl>(scene, options)) {
  Impl& m = *impl_;
  if (!m.occlusion.convex_enclosure()) m.visibility = std::make_unique<Visibility>(m.scene);
  m.sources.resize(scene.patches.size());
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    if (mesh.zero_area(t)) continue;
    const int p = mesh.patch[static_cast<size_t>(t)];
    const Patch& patch = m.scene.patches[static_cast<size_t>(p)];
    const auto& tri = mesh.triangles[static_cast<size_t>(t)];
    const auto corner = [&](int k) { return m.frame.to_local(mesh.positions[static_cast<size_t>(tri[static_cast<size_t>(k)])]); };
    const Triangle triangle = make_triangle(corner(0), corner(1), corner(2), patch.normal);
    if (!(triangle.area > 0.0)) continue;
    SourceTree& s = m.sources[static_cast<size_t>(p)];
    s.triangle.push_back(triangle);
    s.reflected.push_back(glm::max(element[static_cast<size_t>(t)] - scene.material_of(patch).emission, Rgb(0.0)));
  }
  for (size_t p = 0; p < m.sources.size(); ++p) {
    SourceTree& s = m.sources[p];
    const bool reflects = std::any_of(s.reflected.begin(), s.reflected.end(), [](const Rgb& r) { return max3(r) > 0.0; });
    if (!reflects) {
      s = SourceTree{};
      continue;
    }
    const Patch& patch = m.scene.patches[p];
    s.normal = patch.normal;
    s.loops.push_back(m.scene.loop_points(patch.outer));
    for (const auto& h : patch.holes) s.loops.push_back(m.scene.loop_points(h));
    s.order.resize(s.triangle.size());
    for (size_t i = 0; i < s.order.size(); ++i) s.order[i] = static_cast<int>(i);
    s.key.resize(s.triangle.size());
    for (size_t i = 0; i < s.key.size(); ++i) s.key[i] = s.triangle[i].centroid();
    s.key = internal::snapped_keys(s.key);
    s.build(0, static_cast<int>(s.order.size()));
    s.key = {};
    // The triangles in node order: a node's are contiguous in memory (the
    // gather's samples and form factors read them node by node).
    std::vector<Triangle> triangle;
    std::vector<Rgb> reflected;
    for (const int t : s.order) {
      triangle.push_back(s.triangle[static_cast<size_t>(t)]);
      reflected.push_back(s.reflected[static_cast<size_t>(t)]);
    }
    s.triangle.swap(triangle);
    s.reflected.swap(reflected);
    s.order = {};
    s.cumulative.assign(s.triangle.size() + 1, 0.0);
    for (size_t i = 0; i < s.triangle.size(); ++i) s.cumulative[i + 1] = s.cumulative[i] + s.triangle[i].area;
  }
  if (how == GatherSources::clustered ||
      (how == GatherSources::automatic && !gather_every_patch(static_cast<double>(mesh.positions.size()),
                                                                  static_cast<double>(scene.patches.size()))))
    m.build_clusters();
}

FieldEvaluator::~FieldEvaluator() = default;

bool FieldEvaluator::clustered() const { return !impl_->clusters.empty(); }

Vec3 FieldEvaluator::evaluation_point(const Vec3& at, int patch, const Vec3& towards, FieldReport& report) const {
  const Impl& m = *impl_;
  return m.frame.to_scene(m.evaluation_point(m.frame.to_local(at), patch, towards / m.frame.size, report));
}

Vec3 FieldEvaluator::Impl::evaluation_point(const Vec3& x, int patch, const Vec3& inward, FieldReport& report) const {
  const Impl& m = *this;
  const double diagonal = m.diagonal;
  const double length = glm::length(inward);
  const Vec3& normal = m.scene.patches[static_cast<size_t>(patch)].normal;
  // Patches touching x or hanging over it whose whole height above the
  // patch's plane, h, is under a tenth of `inward` (a slab 1 mm thick lying
  // on a floor, a rug 1 mm above it, a lamp hung just under a ceiling):
  // the light around x changes within a few h of them, far less than an
  // element, so the side's value is taken 10 h in (at most a tenth of the
  // way to its triangles' centroid). Taken at x, half lit, it would darken
  // the lit side's interpolation over a whole element. A taller patch touching
  // x (a block standing on the floor) keeps the hair below.
  // Far enough that the shadow rays (single precision) see the side, near
  // enough that the value is the side's limit: 1e-5 of the scene's size, at
  // most a tenth of the way to the centroid of the triangles.
  auto hair_in = [&] { return x + std::min(1e-5 * diagonal / length, 0.1) * inward; };
  const double small = 0.1 * length;
  double step = 0.0;
  bool flat = false;  // touching a patch that lies in the plane (a lamp set in a ceiling)
  // Only the patches near x (a box tree query: this runs once per vertex),
  // in the order of their numbers, as a pass over all of them would go.
  thread_local std::vector<int> near;
  m.occlusion.patches_near(x, std::max(small, 1e-9 * diagonal), near);
  for (const int q : near) {
    if (q == patch) continue;
    const double distance = m.occlusion.distance(q, x);
    const bool touching = distance <= 1e-9 * diagonal;
    if (!touching && !(distance < small)) continue;
    double lo = INFINITY, hi = -INFINITY;
    for (int v : m.scene.patches[static_cast<size_t>(q)].outer) {
      const double h = glm::dot(m.scene.vertices[static_cast<size_t>(v)] - x, normal);
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
    if (lo >= -1e-9 * diagonal && hi > 1e-9 * diagonal && hi < small && distance <= 2.0 * hi) {
      step = std::max(step, std::min(10.0 * hi, small));
      continue;
    }
    if (!touching) continue;
    if (lo >= -1e-9 * diagonal && hi <= 1e-9 * diagonal) {
      flat = true;
      continue;
    }
    ++report.on_other_surface;
    if (length > 0.0) return hair_in();
    // No area around the vertex in its patch (a T-vertex on a crease that
    // only zero-area triangles use): off q within the patch's plane, to
    // the side the patch lies on. Gathered on the crease itself, such a
    // vertex would come out far too dark (a non-convex furnace shows it).
    const Vec3& nq = m.scene.patches[static_cast<size_t>(q)].normal;
    const Vec3 across = nq - glm::dot(nq, normal) * normal;
    if (!(glm::length(across) > 1e-6)) return x;  // q lies in the patch's plane
    const Vec3 hair = 1e-5 * diagonal * glm::normalize(across);
    return m.occlusion.distance(patch, x + hair) <= m.occlusion.distance(patch, x - hair) ? x + hair : x - hair;
  }
  if (step > 0.0) {
    ++report.on_other_surface;
    return x + (step / length) * inward;
  }
  if (flat && length > 0.0) {
    ++report.on_other_surface;
    return hair_in();
  }
  return x;
}

Rgb FieldEvaluator::direct(const Vec3& x, int patch, FieldReport& report) const {
  return impl_->direct.reflected(impl_->frame.to_local(x), patch, &report.direct);
}

namespace internal {

GatherNode gather_node(const std::vector<const Triangle*>& t, const std::vector<Rgb>& r, const Vec3& normal) {
  GatherNode n;
  for (size_t k = 0; k < t.size(); ++k) {
    n.area += t[k]->area;
    n.centre += t[k]->area * t[k]->centroid();
    n.reflected += t[k]->area * r[k];
  }
  n.centre /= n.area;
  n.reflected /= n.area;
  const Vec3 u = glm::normalize(glm::cross(normal, std::abs(normal.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
  const Vec3 w = glm::cross(normal, u);
  double ulo = INFINITY, uhi = -INFINITY, wlo = INFINITY, whi = -INFINITY;
  for (size_t k = 0; k < t.size(); ++k) {
    // A triangle's second moment about c: A/12 (sum d_i d_i^T + S S^T),
    // d_i = v_i - c, S = sum d_i.
    Vec3 sum(0.0);
    glm::dmat3 m(0.0);
    for (const Vec3& v : t[k]->v) {
      const Vec3 d = v - n.centre;
      m += glm::outerProduct(d, d);
      sum += d;
      n.radius = std::max(n.radius, glm::length(d));
      ulo = std::min(ulo, glm::dot(d, u));
      uhi = std::max(uhi, glm::dot(d, u));
      wlo = std::min(wlo, glm::dot(d, w));
      whi = std::max(whi, glm::dot(d, w));
    }
    n.second += (t[k]->area / 12.0) * (m + glm::outerProduct(sum, sum));
    const Vec3 g = t[k]->area * (t[k]->centroid() - n.centre);
    for (int c = 0; c < 3; ++c) n.moment[static_cast<size_t>(c)] += r[k][c] * g;
  }
  n.rect = {n.centre + ulo * u + wlo * w, n.centre + uhi * u + wlo * w, n.centre + uhi * u + whi * w,
            n.centre + ulo * u + whi * w};
  return n;
}

NodeTerm node_term(const GatherNode& node, const Vec3& x, const Vec3& n, const Vec3& m) {
  NodeTerm t;
  const Vec3 r = node.centre - x;
  const double a = glm::dot(n, r), b = -glm::dot(m, r), s = glm::dot(r, r);
  if (!(a > 0.0) || !(b > 0.0)) return t;
  t.f = a * b * node.area / (std::numbers::pi * s * s);
  t.smooth = std::all_of(node.rect.begin(), node.rect.end(), [&](const Vec3& c) { return glm::dot(n, c - x) > 0.0; });
  if (!t.smooth) return t;
  const Vec3 i2r = node.second * r;
  const double trace = node.second[0][0] + node.second[1][1] + node.second[2][2];
  const double s3 = s * s * s;
  const double curvature =
      (-8.0 * b * glm::dot(n, i2r) / s3 + 24.0 * a * b * glm::dot(r, i2r) / (s3 * s) - 4.0 * a * b * trace / s3) /
      std::numbers::pi;
  if (t.f + 0.5 * curvature > 0.0) t.f += 0.5 * curvature;  // else the expansion fails there: the point value stands
  const Vec3 grad = (b * n - a * m - (4.0 * a * b / s) * r) / (std::numbers::pi * s * s);
  for (int c = 0; c < 3; ++c) t.first[c] = glm::dot(grad, node.moment[static_cast<size_t>(c)]);
  return t;
}

}  // namespace internal

// What x (normal n, on `patch`) gathers from source patch q, before its
// reflectance: Lambert's form factor to q x the mean over q's tree cut.
Rgb FieldEvaluator::Impl::gather_patch(size_t q, const Vec3& x, const Vec3& n, int patch, uint64_t id,
                                       double full, FieldReport& report) const {
  const Impl& m = *this;
  // What one entry of a source's tree cut adds: f x its radiosity (send),
  // or f x the mean over its samples [begin .. end) once their rays are cast.
  struct CutTerm {
    double f = 0.0;
    Rgb send{0.0};
    bool sampled = false;
    size_t begin = 0, end = 0;
    double weight = 0.0;  // of the samples
  };
  // Kept per thread: this runs once per (vertex, source).
  thread_local std::vector<int> stack, cut;
  thread_local std::vector<const Triangle*> triangles;
  thread_local std::vector<double> tri_f;
  thread_local std::vector<CutTerm> terms;
  thread_local Samples samples, unshaded;
  thread_local std::vector<Vec3> from;
  thread_local std::vector<unsigned char> seen;
  thread_local ReceiverPoints at_x;  // x alone, for form_factors
  at_x.normal = n;
  at_x.x.assign(1, x);
  at_x.w.assign(1, 1.0);
  const SourceTree& s = m.sources[q];
  if (s.nodes.empty() || static_cast<int>(q) == patch || !m.occlusion.facing(patch, static_cast<int>(q))) return Rgb(0.0);
  const double fq = patch_form_factor(x, n, s.loops, s.normal);
  if (fq <= 0.0) return Rgb(0.0);
  ++report.gather_sources;
  const bool occludable = m.visibility && m.occlusion.may_occlude(patch, static_cast<int>(q));
  // What may lie between x and the parts of q, found once (when a part
  // first needs a shaft test) where the cut has enough parts to pay for
  // it (it costs a few parts' tests); else every part is tested alone
  // (`all`): where faces are cut into few parts (a box field's), listing
  // for every source would cost more than the tests it saves.
  Occlusion::Candidates candidates;
  candidates.all = true;
  bool listed = false;
  // One random stream per (point, source node or triangle).
  const uint64_t stream = pair_seed(id, q);
  // The tree cut: nodes far enough to take whole (>= 0) and the
  // triangles of the leaves opened (-1 - triangle), in the
  // order of the walk; then the triangles' form factors in one pass.
  cut.clear();
  stack.assign(1, 0);
  while (!stack.empty()) {
    const int k = stack.back();
    stack.pop_back();
    const SourceTree::Node& node = s.nodes[static_cast<size_t>(k)];
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) cut.push_back(-1 - i);
    } else if (node.radius <= kOpening * glm::length(node.centre - x)) {
      cut.push_back(k);
    } else {
      stack.push_back(node.left);
      stack.push_back(node.right);
    }
  }
  triangles.clear();
  for (const int e : cut)
    if (e < 0) triangles.push_back(&s.triangle[static_cast<size_t>(-1 - e)]);
  tri_f.resize(triangles.size());
  form_factors(at_x, triangles.data(), triangles.size(), tri_f.data());
  // Per entry of the cut, its weight and what it sends: at once where its
  // shaft is clear, else from samples whose shadow rays are cast
  // together, one Embree call for the whole source.
  terms.clear();
  samples.clear();
  size_t next = 0;
  for (const int e : cut) {
    CutTerm term;
    const int i = -1 - e;
    const bool is_triangle = e < 0;
    const SourceTree::Node* node = is_triangle ? nullptr : &s.nodes[static_cast<size_t>(e)];
    internal::NodeTerm nt;
    if (is_triangle) {
      nt.f = tri_f[next++];
      ++report.gather_triangles;
    } else {
      nt = internal::node_term(*node, x, n, s.normal);
      ++report.gather_nodes;
    }
    if (!(nt.f > 0.0)) continue;
    term.f = nt.f;
    if (occludable && !listed && cut.size() >= kListedParts) {
      candidates = m.occlusion.candidates(patch, x, n, static_cast<int>(q));
      listed = true;
    }
    const bool shaded =
        occludable && (is_triangle ? m.occlusion.may_occlude(candidates, patch, x, n, static_cast<int>(q),
                                                             s.triangle[static_cast<size_t>(i)])
                                   : m.occlusion.may_occlude(candidates, patch, x, n, static_cast<int>(q), node->rect,
                                                             s.normal));
    const int begin = is_triangle ? i : node->begin, end = is_triangle ? i + 1 : node->end;
    const uint64_t seed =
        pair_seed(stream, is_triangle ? (uint64_t{1} << 32) + static_cast<uint64_t>(i) : static_cast<uint64_t>(e));
    if (shaded) {
      term.begin = samples.to.size();
      const Rgb& r = is_triangle ? s.reflected[static_cast<size_t>(i)] : node->reflected;
      const int k = m.rays_for(term.f * max3(r), full);
      term.weight = m.draw(x, n, s, begin, end, seed, k, samples);
      term.end = samples.to.size();
      term.sampled = true;
      report.rays_cast += k;
    } else if (is_triangle) {
      term.send = term.f * s.reflected[static_cast<size_t>(i)];
    } else if (nt.smooth) {
      term.send = term.f * node->reflected + nt.first;
    } else {
      // The node straddles x's tangent plane (the expansion fails): the
      // same points, without rays (the shaft is clear).
      unshaded.clear();
      const double w = m.draw(x, n, s, begin, end, seed, m.rays_per_node, unshaded);
      term.send = term.f * sampled_mean(unshaded, 0, unshaded.to.size(), nullptr, w);
    }
    terms.push_back(term);
  }
  seen.assign(samples.to.size(), 1);
  if (!samples.to.empty()) {
    from.assign(samples.to.size(), x);
    m.visibility->visible(from.data(), samples.to.data(), samples.to.size(), patch, static_cast<int>(q), seen.data());
  }
  double weight = 0.0;
  Rgb sum(0.0);
  for (const CutTerm& t : terms) {
    weight += t.f;
    sum += t.sampled ? t.f * sampled_mean(samples, t.begin, t.end, seen.data(), t.weight) : t.send;
  }
  return weight > 0.0 ? (fq / weight) * sum : Rgb(0.0);
}

Rgb FieldEvaluator::indirect(const Vec3& at, int patch, uint64_t id, FieldReport& report, double solved) const {
  const Impl& m = *impl_;
  const Vec3 x = m.frame.to_local(at);
  const Patch& receiver = m.scene.patches[static_cast<size_t>(patch)];
  const Rgb rho = m.scene.material_of(receiver).reflectance;
  if (max3(rho) <= 0.0) return Rgb(0.0);
  const Vec3& n = receiver.normal;
  const double full = kRayShare * solved;
  if (!m.clusters.empty()) return rho * m.gather_clustered(x, n, patch, id, full, report);
  Rgb h(0.0);
  for (size_t q = 0; q < m.sources.size(); ++q) h += m.gather_patch(q, x, n, patch, id, full, report);
  return rho * h;
}

Rgb FieldEvaluator::radiosity(const Vec3& x, int patch, uint64_t id, FieldReport& report) const {
  return impl_->scene.material_of(patch).emission + direct(x, patch, report) + indirect(x, patch, id, report);
}

namespace internal {

void display_sides(const Mesh& mesh, const NodalField& field, std::vector<int>& patch, std::vector<Vec3>& inward) {
  const size_t nd = field.points.size();
  patch.assign(nd, -1);
  inward.assign(nd, Vec3(0.0));
  std::vector<std::vector<std::pair<int, double>>> area(nd);  // (patch, area) per display vertex
  for (int t = 0; t < mesh.triangle_count(); ++t)
    for (int d : field.corners[static_cast<size_t>(t)]) {
      auto& list = area[static_cast<size_t>(d)];
      const int p = mesh.patch[static_cast<size_t>(t)];
      auto it = std::find_if(list.begin(), list.end(), [&](const auto& e) { return e.first == p; });
      if (it == list.end()) it = list.insert(list.end(), {p, 0.0});
      it->second += mesh.area(t);
    }
  for (size_t d = 0; d < nd; ++d)
    patch[d] = std::max_element(area[d].begin(), area[d].end(),
                                [](const auto& a, const auto& b) { return a.second < b.second; })->first;
  std::vector<Vec3> towards(nd, Vec3(0.0));
  std::vector<double> weight(nd, 0.0);
  // Zero-area triangles (closing T-vertices) give no direction: their
  // centroid lies on an edge through the vertex, and what the difference
  // leaves is rounding. A vertex only they use has no inward direction.
  for (int t = 0; t < mesh.triangle_count(); ++t)
    for (int d : field.corners[static_cast<size_t>(t)])
      if (mesh.patch[static_cast<size_t>(t)] == patch[static_cast<size_t>(d)] && !mesh.zero_area(t)) {
        towards[static_cast<size_t>(d)] += mesh.area(t) * mesh.centroid(t);
        weight[static_cast<size_t>(d)] += mesh.area(t);
      }
  for (size_t d = 0; d < nd; ++d)
    if (weight[d] > 0.0) inward[d] = towards[d] / weight[d] - field.points[d];
}

void add_counts(FieldReport& to, const FieldReport& from) {
  to.direct += from.direct;
  to.on_other_surface += from.on_other_surface;
  to.gather_sources += from.gather_sources;
  to.gather_nodes += from.gather_nodes;
  to.gather_clusters += from.gather_clusters;
  to.gather_triangles += from.gather_triangles;
  to.rays_cast += from.rays_cast;
}

BoxTree triangle_boxes(const Mesh& mesh) {
  std::vector<Box3> boxes(mesh.triangles.size());
  for (size_t t = 0; t < boxes.size(); ++t)
    for (const int v : mesh.triangles[t]) boxes[t].add(mesh.positions[static_cast<size_t>(v)]);
  return BoxTree(boxes);
}

bool inside_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double tol) {
  const Vec3 n = glm::cross(b - a, c - a);
  const double nn = glm::dot(n, n);
  if (nn <= 0.0) return false;
  const double u = glm::dot(glm::cross(c - b, p - b), n) / nn;
  const double v = glm::dot(glm::cross(a - c, p - c), n) / nn;
  return u >= -tol && v >= -tol && 1.0 - u - v >= -tol;
}

}  // namespace internal

NodalField compute_field(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                         const SolveOptions& options, FieldReport* report, const ProgressFn& progress) {
  FieldReport rep;
  rep.mode = resolve_field_mode(options.field, scene, mesh, &rep.why);
  if (rep.mode != FieldMode::gather) {
    if (report) *report = rep;
    return compute_nodal(scene, mesh, element, options.crease_angle, nodal_method(rep.mode));
  }
  // The display vertices (and where each one's triangles lie), then every
  // value anew.
  NodalField field = compute_nodal(scene, mesh, element, options.crease_angle, NodalMethod::mean);
  const size_t nd = field.points.size();
  rep.display_vertices = static_cast<long long>(nd);
  std::vector<int> patch;
  std::vector<Vec3> inward;
  internal::display_sides(mesh, field, patch, inward);

  const FieldEvaluator evaluator(scene, mesh, element, options);
  rep.clustered = evaluator.clustered();
  std::vector<FieldReport> per(nd);
  std::vector<Rgb> direct(nd), indirect(nd);
  // In blocks, so that progress is reported from one thread.
  const size_t blocks = std::min<size_t>(nd, 50);
  auto pass = [&](const char* phase, double& seconds, auto&& body) {
    const auto t0 = std::chrono::steady_clock::now();
    run_in_arena(options.threads, [&] {
      for (size_t b = 0; b < blocks; ++b) {
        tbb::parallel_for(b * nd / blocks, (b + 1) * nd / blocks, body);
        if (progress) progress(phase, static_cast<double>(b + 1) / static_cast<double>(blocks));
      }
    });
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  std::vector<Vec3> at(nd);
  pass("direct", rep.seconds_direct, [&](size_t d) {
    at[d] = evaluator.evaluation_point(field.points[d], patch[d], inward[d], per[d]);
    direct[d] = evaluator.direct(at[d], patch[d], per[d]);
  });
  pass("gather", rep.seconds_gather, [&](size_t d) {
    // The solve's value there: the mean of the elements around the vertex.
    const Material& m = scene.material_of(patch[d]);
    const double rho = max3(m.reflectance);
    const double solved = rho > 0.0 ? std::max(0.0, max3(field.radiosity[d] - m.emission)) / rho : 0.0;
    indirect[d] = evaluator.indirect(at[d], patch[d], static_cast<uint64_t>(d), per[d], solved);
  });
  for (size_t d = 0; d < nd; ++d) {
    field.radiosity[d] = scene.material_of(patch[d]).emission + direct[d] + indirect[d];
    internal::add_counts(rep, per[d]);
  }
  if (report) *report = rep;
  return field;
}

namespace {

// Area-weighted means per patch of a per-triangle value.
template <class Value>
std::vector<Rgb> patch_means(const Scene& scene, const Mesh& mesh, Value&& value) {
  std::vector<Rgb> sum(scene.patches.size(), Rgb(0.0));
  std::vector<double> area(scene.patches.size(), 0.0);
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const size_t p = static_cast<size_t>(mesh.patch[static_cast<size_t>(t)]);
    const double a = mesh.area(t);
    sum[p] += a * value(t);
    area[p] += a;
  }
  for (size_t p = 0; p < sum.size(); ++p)
    if (area[p] > 0.0) sum[p] /= area[p];
  return sum;
}

}  // namespace

std::vector<Rgb> patch_mean_radiosity(const Scene& scene, const Mesh& mesh, const NodalField& field) {
  const bool sampled = field.triangle_mean.size() == mesh.triangles.size();
  return patch_means(scene, mesh, [&](int t) {
    if (sampled) return field.triangle_mean[static_cast<size_t>(t)];
    Rgb mean(0.0);
    for (int d : field.corners[static_cast<size_t>(t)]) mean += field.radiosity[static_cast<size_t>(d)] / 3.0;
    return mean;
  });
}

std::vector<Rgb> patch_mean_radiosity(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element) {
  return patch_means(scene, mesh, [&](int t) { return element[static_cast<size_t>(t)]; });
}

std::vector<Rgb> element_patch_means(const Scene& scene, const Mesh& mesh, const Solution& solution) {
  return solution.element_patch_mean.empty() ? patch_mean_radiosity(scene, mesh, solution.element)
                                             : solution.element_patch_mean;
}

}  // namespace radmesh
