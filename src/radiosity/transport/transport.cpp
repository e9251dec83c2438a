// The transport core every method shares: the element set (triangle,
// patch, material), the visibility estimator (shadow rays where the shaft
// holds an occluder), the energy balance and the sweeps' stopping rule
// with its Aitken extrapolation.

#include "radiosity/transport/transport.h"

#include "radmesh/errors.h"
#include "radiosity/transport/occlusion.h"
#include "radiosity/transport/sampling.h"
#include "radiosity/transport/visibility.h"

#include <tbb/task_arena.h>

#include <array>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <mutex>
#include <optional>
#include <string>

namespace radmesh {

void ElementSet::add(const Scene& scene, int p, const Vec3& a, const Vec3& b, const Vec3& c, bool zero_area_flag) {
  const Patch& patch = scene.patches[static_cast<size_t>(p)];
  const Material& m = scene.material_of(patch);
  triangle.push_back(make_triangle(a, b, c, patch.normal));
  this->patch.push_back(p);
  reflectance.push_back(m.reflectance);
  emission.push_back(m.emission);
  zero_area.push_back(zero_area_flag ? 1 : 0);
}

ElementSet make_elements(const Scene& scene, const Mesh& mesh) {
  ElementSet e;
  const size_t n = mesh.triangles.size();
  e.triangle.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& t = mesh.triangles[i];
    e.add(scene, mesh.patch[i], mesh.positions[static_cast<size_t>(t[0])], mesh.positions[static_cast<size_t>(t[1])],
          mesh.positions[static_cast<size_t>(t[2])], mesh.zero_area(static_cast<int>(i)));
  }
  return e;
}

Vec3 tangent_of(const Vec3& n) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(n[i]) < std::abs(n[k])) k = i;
  Vec3 axis(0.0);
  axis[k] = 1.0;
  return glm::normalize(axis - glm::dot(axis, n) * n);
}

namespace {

// Whether every one of the 7 rays from point x of patch `patch` meets the
// back of a face first (inside_closed_object).
bool shut_in(const Scene& scene, const Visibility& vis, const Vec3& x, int patch) {
  const Vec3 n = scene.patches[static_cast<size_t>(patch)].normal;
  const Vec3 u = tangent_of(n), v = glm::cross(n, u);
  for (int r = 0; r < 7; ++r) {
    Vec3 d = n;
    if (r > 0) {
      const double phi = (r - 1) * std::numbers::pi / 3.0;
      d = 0.5 * n + 0.8660254037844386 * (std::cos(phi) * u + std::sin(phi) * v);
    }
    if (vis.ray_end(x, d, patch) != Visibility::RayEnd::back) return false;  // nothing, or a front face
  }
  return true;
}

}  // namespace

bool inside_closed_object(const Scene& scene, const Visibility& vis, const std::array<Vec3, 3>& v, int patch) {
  const Vec3 c = (v[0] + v[1] + v[2]) / 3.0;
  if (!shut_in(scene, vis, c, patch)) return false;
  for (const Vec3& corner : v)
    if (!shut_in(scene, vis, corner + 0.05 * (c - corner), patch)) return false;
  return true;
}

std::vector<char> emitting_inside_objects(const Scene& scene, const ElementSet& el, const Visibility& vis) {
  std::vector<char> inside(el.size(), 0);
  for (size_t e = 0; e < el.size(); ++e)
    if (max3(el.emission[e]) > 0.0 && !el.zero_area[e])
      inside[e] = inside_closed_object(scene, vis, el.triangle[e].v, el.patch[e]) ? 1 : 0;
  return inside;
}

std::vector<std::string> enclosed_emitter_warnings(const Scene& scene, const ElementSet& el,
                                                   const std::vector<char>& inside) {
  std::vector<double> area(scene.patches.size(), 0.0), shut(scene.patches.size(), 0.0);
  for (size_t e = 0; e < el.size(); ++e) {
    const size_t p = static_cast<size_t>(el.patch[e]);
    area[p] += el.triangle[e].area;
    if (inside[e] && max3(el.emission[e]) > 0.0) shut[p] += el.triangle[e].area;
  }
  std::vector<std::string> out;
  for (size_t p = 0; p < area.size(); ++p) {
    if (!(shut[p] > 0.0)) continue;
    const Patch& patch = scene.patches[p];
    const double percent = std::round(1000.0 * shut[p] / area[p]) / 10.0;
    out.push_back(where(patch.file, patch.line) + "emitting face '" + patch.name + "': " + format_number(percent) +
                  "% of its area (" + format_number(shut[p]) + " of " + format_number(area[p]) +
                  ") lies inside a closed object (every ray from there meets the back of a face): the light it "
                  "emits there goes into the object and is counted as escaped power");
  }
  return out;
}

struct VisibilityEstimator::Impl {
  explicit Impl(const Scene& scene) : occlusion(scene) {
    if (!occlusion.convex_enclosure()) embree.emplace(scene);
  }
  Occlusion occlusion;
  std::optional<Visibility> embree;  // none in a convex enclosure (until rays() asks)
  std::once_flag built;
  const Scene* scene = nullptr;
};

VisibilityEstimator::VisibilityEstimator(const Scene& scene, int rays)
    : impl_(std::make_unique<Impl>(scene)), side_(strata_side(rays)) {
  impl_->scene = &scene;
}

const Visibility& VisibilityEstimator::rays() const {
  std::call_once(impl_->built, [&] {
    if (!impl_->embree) impl_->embree.emplace(*impl_->scene);
  });
  return *impl_->embree;
}

VisibilityEstimator::~VisibilityEstimator() = default;

void VisibilityEstimator::visible(const Vec3* x, const Vec3* nx, const Vec3* y, const Vec3* ny, const int* pa,
                                  const int* pb, size_t n, unsigned char* seen) const {
  if (!impl_->embree) {
    std::fill(seen, seen + n, static_cast<unsigned char>(1));
    return;
  }
  if (n > 0) impl_->embree->visible_off_surfaces_each(x, nx, y, ny, pa, pb, n, seen);
}

bool VisibilityEstimator::convex_enclosure() const { return impl_->occlusion.convex_enclosure(); }
bool VisibilityEstimator::facing(int p, int q) const { return impl_->occlusion.facing(p, q); }
double VisibilityEstimator::distance_to_patch(int p, const Vec3& x) const { return impl_->occlusion.distance(p, x); }

double VisibilityEstimator::visible_fraction(const Triangle& a, int pa, uint64_t id_a, const Triangle& b, int pb,
                                             uint64_t id_b, RayCount& count, int side, bool test_shaft) const {
  if (side <= 0) side = side_;
  const int rays = side * side;
  if (!impl_->embree || (test_shaft && !impl_->occlusion.may_occlude(pa, pb, a, b))) {
    count.skipped += rays;
    ++count.unoccludable;
    return 1.0;
  }
  // The pair in increasing id order: the same rays whichever asks.
  const bool swap = id_b < id_a;
  const Triangle& ti = swap ? b : a;
  const Triangle& tj = swap ? a : b;
  const int pi = swap ? pb : pa, pj = swap ? pa : pb;
  SplitMix rng(pair_seed(swap ? id_b : id_a, swap ? id_a : id_b));
  std::array<int, 4096> perm;  // rays <= 4096 (check_solve_options)
  std::iota(perm.begin(), perm.begin() + rays, 0);
  for (int k = rays - 1; k > 0; --k)
    std::swap(perm[static_cast<size_t>(k)], perm[static_cast<size_t>(rng.next() % static_cast<uint64_t>(k + 1))]);
  thread_local std::vector<Vec3> xs, ys;
  thread_local std::vector<unsigned char> seen;
  xs.resize(static_cast<size_t>(rays));
  ys.resize(static_cast<size_t>(rays));
  seen.resize(static_cast<size_t>(rays));
  for (int k = 0; k < rays; ++k) {
    const int s = k, t = perm[static_cast<size_t>(k)];
    // Each point's second coordinate is drawn first, in an order written out
    // (the order of evaluating function arguments is unspecified).
    const double xv = ((s / side) + rng.uniform()) / side;
    const double xu = ((s % side) + rng.uniform()) / side;
    xs[static_cast<size_t>(k)] = triangle_point(ti.v[0], ti.v[1], ti.v[2], xu, xv);
    const double yv = ((t / side) + rng.uniform()) / side;
    const double yu = ((t % side) + rng.uniform()) / side;
    ys[static_cast<size_t>(k)] = triangle_point(tj.v[0], tj.v[1], tj.v[2], yu, yv);
  }
  impl_->embree->visible_off_surfaces(xs.data(), ti.normal, ys.data(), tj.normal, xs.size(), pi, pj, seen.data());
  int open = 0;
  double weight = 0.0, open_weight = 0.0;
  for (size_t k = 0; k < xs.size(); ++k) {
    const bool visible = seen[k] != 0;
    open += visible;
    // Light passes between x and y only when each lies in front of the
    // other's plane; a ray behind either one (an element straddling the
    // other's plane) crosses what the exchange never does and says nothing.
    const double w = point_kernel(xs[k], ti.normal, ys[k], tj.normal);
    if (w > 0.0 && std::isfinite(w)) {
      weight += w;
      if (visible) open_weight += w;
    }
  }
  count.cast += rays;
  return weight > 0.0 ? open_weight / weight : static_cast<double>(open) / rays;
}

void BalanceAccumulator::add(double area, const Rgb& rho, const Rgb& emission, const Rgb& b, const Rgb& h,
                             double row_sum, double sent_row) {
  emitted_ += emission * area;
  absorbed_ += (Rgb(1.0) - rho) * h * area;
  escaped_ += b * area * (1.0 - sent_row);
  worst_ = glm::max(worst_, glm::abs(emission + rho * h - b));
  contraction_ = glm::max(contraction_, rho * row_sum);
  largest_ = glm::max(largest_, glm::abs(b));
}

void BalanceAccumulator::finish(SolveStats& st) const {
  st.power_emitted = emitted_;
  st.power_absorbed = absorbed_;
  st.power_escaped = escaped_;
  for (int c = 0; c < 3; ++c) {
    const double r = largest_[c] > 0.0 ? worst_[c] / largest_[c] : 0.0;
    st.residual[static_cast<size_t>(c)] = r;
    st.error_bound[static_cast<size_t>(c)] = contraction_[c] < 1.0 ? r / (1.0 - contraction_[c]) : -1.0;
  }
}

SweepMonitor::Action SweepMonitor::after_sweep(double change, double top) {
  if (change <= 0.0) return Action::stop;  // a fixed point
  if (previous_ > 0.0) {
    ratios_[static_cast<size_t>(count_ % 3)] = change / previous_;
    ++count_;
  }
  previous_ = change;
  const double allowed = tolerance_ * top;
  if (change > allowed) return maybe_extrapolate();
  if (contraction_ < 1.0 && change * contraction_ / (1.0 - contraction_) <= allowed) return Action::stop;
  if (steady() && q_ < 1.0 && change * q_ / (1.0 - q_) <= allowed) return Action::stop;
  return maybe_extrapolate();
}

bool SweepMonitor::steady() {
  if (count_ < 3) return false;
  const auto [lo, hi] = std::minmax_element(ratios_.begin(), ratios_.end());
  q_ = *hi;
  return *hi - *lo <= 0.01 * *hi;
}

SweepMonitor::Action SweepMonitor::maybe_extrapolate() {
  if (!steady() || q_ <= 0.5 || q_ >= 1.0) return Action::go_on;
  ++extrapolations_;
  previous_ = 0.0;
  count_ = 0;
  return Action::extrapolate;
}

void run_in_arena(int threads, const std::function<void()>& f) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute(f);
}

void report_visibility_skips(SolveStats& st, const char* pair_kind) {
  if (st.convex_enclosure)
    st.skips.push_back("visibility: the scene is one convex enclosure, so no shadow ray was cast");
  else if (st.pairs_unoccludable > 0)
    st.skips.push_back("visibility: " + std::to_string(st.pairs_unoccludable) + " " + pair_kind +
                       " pairs have no patch in their shaft; their rays were not cast");
}

}  // namespace radmesh
