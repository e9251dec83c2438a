// The display refined by its own interpolation error (refine_display). The
// solver's mesh is the root of an element tree; each round gives every new
// display vertex its value, evaluates the field at the midpoints of the
// edges of the display triangles that may still be split, and splits the
// triangles where the linear interpolation of the edge's ends misses a
// midpoint by more than the tolerance. One FieldEvaluator over the solver's
// elements serves every round: the display shows the solution more finely,
// it never changes what was solved.

#include "radmesh/field.h"
#include "radmesh/hierarchy.h"

#include "field/field_impl.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <climits>
#include <unordered_map>
#include <unordered_set>

namespace radmesh {

namespace {

// A display vertex across rounds: its tree vertex and the smallest root
// among the triangles of its side (the two sides of a discontinuity line
// lie in different roots, since its edges are the initial mesh's).
uint64_t vertex_key(int vertex, int root) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(vertex)) << 32) | static_cast<uint32_t>(root);
}

// The display holds at most this many times the solver's triangles (of
// positive area, as the display's are counted).
constexpr double kDisplayGrowth = 2.0;
// Past the budget, a round takes half the splits left, or all of them once
// they are this few (each round rebuilds the whole display).
constexpr long long kLastRoom = 256;

// A random stream's seed for a midpoint: its edge and root, mixed.
uint64_t midpoint_seed(int a, int b, int root) {
  uint64_t z = (static_cast<uint64_t>(static_cast<uint32_t>(std::min(a, b))) << 32) ^
               static_cast<uint32_t>(std::max(a, b)) ^ (static_cast<uint64_t>(static_cast<uint32_t>(root)) << 17);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (z ^ (z >> 31)) | (uint64_t{1} << 63);  // apart from the display vertices' seeds
}

// A point the field is evaluated at.
struct Point {
  Vec3 x;
  int patch = -1;
  Vec3 inward{0.0};  // into the triangles whose value it is
  uint64_t seed = 0;
  double solved = 0.0;  // FieldEvaluator::indirect's `solved`
};

// What the solve puts at a point of an element of radiosity `b`, for
// FieldEvaluator::indirect.
double solved_at(const Scene& scene, int patch, const Rgb& b) {
  const Material& m = scene.material_of(patch);
  const double rho = max3(m.reflectance);
  return rho > 0.0 ? std::max(0.0, max3(b - m.emission)) / rho : 0.0;
}

class Refinement {
public:
  Refinement(const Scene& scene, const Mesh& initial, const Mesh& mesh, const std::vector<Rgb>& element,
             const SolveOptions& options, FieldReport& report)
      : scene_(scene), transport_(mesh), element_(element), options_(options), report_(report),
        evaluator_(scene, transport_, element_, options), tree_(initial),
        boxes_(internal::triangle_boxes(transport_)) {
    report_.clustered = evaluator_.clustered();
  }

  // The solver's element (of `patch`) that point x lies in: the first the
  // box query finds whose triangle holds it, or where none does (x on no
  // element of positive area up to rounding), the nearest by centroid
  // among those it finds, else the patch's first.
  int element_at(const Vec3& x, int patch) const {
    const double eps = 1e-9 * scene_.diagonal();
    Box3 at;
    at.add(x);
    int best = -1;
    double nearest = INFINITY;
    boxes_.overlapping(at, eps, [&](int t) {
      if (transport_.patch[static_cast<size_t>(t)] != patch || !(transport_.area(t) > 0.0)) return true;
      const auto& tri = transport_.triangles[static_cast<size_t>(t)];
      if (internal::inside_triangle(x, transport_.positions[static_cast<size_t>(tri[0])],
                                    transport_.positions[static_cast<size_t>(tri[1])],
                                    transport_.positions[static_cast<size_t>(tri[2])], 1e-9)) {
        best = t;
        return false;
      }
      const double d = glm::length(transport_.centroid(t) - x);
      if (d < nearest) nearest = d, best = t;
      return true;
    });
    if (best >= 0) return best;
    for (int t = 0; t < transport_.triangle_count(); ++t)
      if (transport_.patch[static_cast<size_t>(t)] == patch) return t;
    return 0;
  }

  // B at each point: the direct pass, then the gather, in parallel; the
  // seeds make the values independent of the thread count.
  std::vector<Rgb> evaluate(const std::vector<Point>& points) {
    const size_t n = points.size();
    std::vector<FieldReport> per(n);
    std::vector<Vec3> at(n);
    std::vector<Rgb> b(n);
    auto pass = [&](double& seconds, auto&& body) {
      const auto t0 = std::chrono::steady_clock::now();
      run_in_arena(options_.threads, [&] { tbb::parallel_for(size_t(0), n, body); });
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    pass(report_.seconds_direct, [&](size_t k) {
      const Point& p = points[k];
      at[k] = evaluator_.evaluation_point(p.x, p.patch, p.inward, per[k]);
      b[k] = scene_.material_of(p.patch).emission + evaluator_.direct(at[k], p.patch, per[k]);
    });
    pass(report_.seconds_gather, [&](size_t k) {
      const Point& p = points[k];
      b[k] += evaluator_.indirect(at[k], p.patch, p.seed, per[k], p.solved);
    });
    for (const FieldReport& r : per) internal::add_counts(report_, r);
    return b;
  }

  // The display of the tree's leaves now: its mesh, elements and field,
  // every display vertex valued (those new since the last round evaluated).
  void show(Mesh& mesh, std::vector<Rgb>& element, std::vector<int>& origin, NodalField& field) {
    std::vector<int> leaf_of;
    mesh = tree_.conforming_mesh(&leaf_of);
    element.assign(mesh.triangles.size(), Rgb(0.0));
    origin.assign(mesh.triangles.size(), -1);
    leaf_.assign(mesh.triangles.size(), -1);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      leaf_[t] = leaf_of[t];
      // A zero-area triangle closing a T-vertex follows its leaf, which
      // conforming_mesh puts before it.
      origin[t] = leaf_of[t] >= 0 ? element_at(mesh.centroid(static_cast<int>(t)), mesh.patch[t]) : origin[t - 1];
      element[t] = element_[static_cast<size_t>(origin[t])];
    }
    field = compute_nodal(scene_, mesh, element, options_.crease_angle, NodalMethod::mean);
    std::vector<int> patch;
    std::vector<Vec3> inward;
    internal::display_sides(mesh, field, patch, inward);
    const size_t nd = field.points.size();
    std::vector<int> vertex(nd, -1), root(nd, INT_MAX);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const size_t d = static_cast<size_t>(field.corners[t][static_cast<size_t>(k)]);
        vertex[d] = mesh.triangles[t][static_cast<size_t>(k)];
        if (leaf_[t] >= 0 && mesh.area(static_cast<int>(t)) > 0.0)
          root[d] = std::min(root[d], tree_.node(leaf_[t]).root);
      }
    std::vector<Point> missing;
    std::vector<size_t> which;
    for (size_t d = 0; d < nd; ++d)
      if (!value_.count(vertex_key(vertex[d], root[d]))) {
        which.push_back(d);
        missing.push_back({field.points[d], patch[d], inward[d], vertex_key(vertex[d], root[d]),
                           solved_at(scene_, patch[d], field.radiosity[d])});
      }
    const std::vector<Rgb> b = evaluate(missing);
    for (size_t k = 0; k < which.size(); ++k) value_[missing[k].seed] = b[k];
    for (size_t d = 0; d < nd; ++d) field.radiosity[d] = value_.at(vertex_key(vertex[d], root[d]));
    report_.display_vertices = static_cast<long long>(nd);
  }

  // Evaluates the midpoints of the leaves' edges, which give every leaf its
  // mean, and splits the leaves the interpolation misses there by more than
  // the tolerance, unless they are at kDisplayLevels, within the display's
  // budget: the means hold wherever the refinement stops. Returns the
  // number of splits.
  long long split(const Mesh& mesh, const std::vector<Rgb>& element, const NodalField& field) {
    means_.clear();
    double largest = 0.0;  // the largest reflected radiosity shown
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int d : field.corners[t])
        largest = std::max(largest, max3(field.radiosity[static_cast<size_t>(d)] -
                                         scene_.material_of(mesh.patch[t]).emission));
    if (!(largest > 0.0)) return 0;
    const double miss = options_.display_tolerance * largest;
    // The candidates, one per edge and root (two leaves of one root share
    // an edge's side), in leaf order.
    std::vector<Point> points;
    std::unordered_set<uint64_t> asked;  // this round's midpoint seeds
    std::vector<std::array<uint64_t, 3>> of(mesh.triangles.size());  // midpoint seeds
    std::vector<size_t> leaves;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const int n = leaf_[t];
      if (n < 0 || !(mesh.area(static_cast<int>(t)) > 0.0)) continue;
      leaves.push_back(t);
      const int root = tree_.node(n).root;
      for (int k = 0; k < 3; ++k) {
        const int a = mesh.triangles[t][static_cast<size_t>(k)], b = mesh.triangles[t][static_cast<size_t>((k + 1) % 3)];
        const uint64_t seed = midpoint_seed(a, b, root);
        if (asked.insert(seed).second && !midpoint_.count(seed)) {
          const Vec3 x = 0.5 * (mesh.positions[static_cast<size_t>(a)] + mesh.positions[static_cast<size_t>(b)]);
          points.push_back({x, mesh.patch[t], mesh.centroid(static_cast<int>(t)) - x, seed,
                            solved_at(scene_, mesh.patch[t], element[t])});
        }
        of[t][static_cast<size_t>(k)] = seed;
      }
    }
    // Midpoints evaluated in an earlier round keep their values: a leaf
    // that passed the test then passes it again.
    const std::vector<Rgb> values = evaluate(points);
    for (size_t k = 0; k < points.size(); ++k) midpoint_.emplace(points[k].seed, values[k]);
    report_.display_midpoints += static_cast<long long>(points.size());
    auto b = [&](uint64_t seed) { return midpoint_.at(seed); };
    // Each triangle's mean: its midpoints' (exact for a quadratic field)
    // where they were sampled, its corners' otherwise.
    means_.assign(mesh.triangles.size(), Rgb(0.0));
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int d : field.corners[t]) means_[t] += field.radiosity[static_cast<size_t>(d)] / 3.0;
    for (const size_t t : leaves) {
      means_[t] = Rgb(0.0);
      for (int k = 0; k < 3; ++k) means_[t] += b(of[t][static_cast<size_t>(k)]) / 3.0;
    }
    // The leaves the interpolation misses, with their largest miss.
    std::vector<std::pair<double, size_t>> flagged;
    for (const size_t t : leaves) {
      if (tree_.node(leaf_[t]).level >= kDisplayLevels) continue;
      double worst = 0.0;
      for (int k = 0; k < 3; ++k) {
        const Rgb ends = 0.5 * (field.radiosity[static_cast<size_t>(field.corners[t][static_cast<size_t>(k)])] +
                                field.radiosity[static_cast<size_t>(field.corners[t][static_cast<size_t>((k + 1) % 3)])]);
        worst = std::max(worst, max3(glm::abs(b(of[t][static_cast<size_t>(k)]) - ends)));
      }
      if (worst > miss) flagged.emplace_back(worst, t);
    }
    // All of them while they take at most half of the budget left (a split
    // adds three triangles; all of what is left once that is kLastRoom
    // splits or fewer), else the largest misses first up to that: the
    // others are tested again with the children of those split, so that a
    // shadow's edge goes deeper before a smooth field's broad misses use up
    // the display.
    const long long room = static_cast<long long>((budget - static_cast<double>(leaves.size())) / 3.0);
    const size_t allowed = static_cast<size_t>(std::max(0LL, room > kLastRoom ? room / 2 : room));
    if (flagged.size() > allowed) {
      std::sort(flagged.begin(), flagged.end(),
                [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); });
      flagged.resize(allowed);
      std::sort(flagged.begin(), flagged.end(), [](const auto& x, const auto& y) { return x.second < y.second; });
    }
    long long splits = 0;
    for (const auto& [by, t] : flagged) {
      const int n = leaf_[t], root = tree_.node(n).root;
      const auto corners = tree_.node(n).v;
      tree_.split(n);
      ++splits;
      // The midpoints' values serve the new vertices, on this root's side.
      for (int k = 0; k < 3; ++k) {
        const int a = corners[static_cast<size_t>(k)], c = corners[static_cast<size_t>((k + 1) % 3)];
        value_.emplace(vertex_key(tree_.midpoint(root, a, c), root), b(of[t][static_cast<size_t>(k)]));
      }
    }
    report_.display_splits += splits;
    return splits;
  }

private:
  const Scene& scene_;
  const Mesh transport_;            // the solver's mesh and elements, which the evaluator
  const std::vector<Rgb> element_;  // gathers from while the display is rebuilt
  const SolveOptions& options_;
  FieldReport& report_;
  const FieldEvaluator evaluator_;
  ElementTree tree_;
  BoxTree boxes_;  // over the solver's triangles
  std::vector<int> leaf_;  // per display triangle: its leaf, -1 for a zero-area one
  std::unordered_map<uint64_t, Rgb> value_;     // per vertex_key
  std::unordered_map<uint64_t, Rgb> midpoint_;  // per midpoint_seed
  std::vector<Rgb> means_;  // per display triangle of the last split's mesh (see split)

public:
  double budget = 0.0;  // display triangles of positive area past which no round splits
  // The means of the last split's triangles, when it sampled them.
  std::vector<Rgb> take_means() { return std::move(means_); }
};

}  // namespace

NodalField refine_display(const Scene& scene, const Mesh& initial, Mesh& mesh, std::vector<Rgb>& element,
                          std::vector<int>& origin, const SolveOptions& options, FieldReport* report,
                          const ProgressFn& progress) {
  FieldReport rep;
  rep.mode = FieldMode::gather;
  Refinement refinement(scene, initial, mesh, element, options, rep);
  // The display's size is bounded by the solver's: a few times its triangles.
  auto with_area = [](const Mesh& m) {  // zero-area closures left out
    double n = 0.0;
    for (int t = 0; t < m.triangle_count(); ++t) n += m.zero_area(t) ? 0.0 : 1.0;
    return n;
  };
  refinement.budget = kDisplayGrowth * std::max(with_area(initial), with_area(mesh));
  NodalField field;
  // A round splits every leaf it flags, whose children are a level down (at
  // most kDisplayLevels rounds of those), or past the budget half of what
  // is left of it: the rounds end.
  for (int round = 0;; ++round) {
    refinement.show(mesh, element, origin, field);
    if (progress) progress("display", std::min(1.0, (round + 1.0) / (kDisplayLevels + 2.0)));
    rep.display_rounds = round + 1;
    if (refinement.split(mesh, element, field) == 0) {
      field.triangle_mean = refinement.take_means();
      break;
    }
  }
  if (report) *report = rep;
  return field;
}

}  // namespace radmesh
