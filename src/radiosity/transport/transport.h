// The transport core every solver and the probes share: the element set, the
// visibility estimator, the energy balance and residual, and the thread arena
// a call runs in. Lambert's contour sum is in form_factor.h.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/form_factor.h"
#include "radmesh/solution.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace radmesh {

class Visibility;

// Elements as the solvers see them: per element its triangle (vertices, the
// patch normal, area), patch, material values and zero-area flag. A
// zero-area element never enters a form factor, never receives or shoots.
struct ElementSet {
  std::vector<Triangle> triangle;
  std::vector<int> patch;
  std::vector<Rgb> reflectance, emission;
  std::vector<char> zero_area;

  size_t size() const { return triangle.size(); }
  // Appends one element of patch `p` with corners a, b, c.
  void add(const Scene& scene, int p, const Vec3& a, const Vec3& b, const Vec3& c, bool zero_area_flag = false);
};

// Every triangle of `mesh`, in order (zero-area ones flagged, Mesh::zero_area).
ElementSet make_elements(const Scene& scene, const Mesh& mesh);

// The tangent u of a plane with normal n: the coordinate axis least aligned
// with n, made perpendicular, so that axis-aligned walls get axis-aligned
// frames (the pixmaps' grids).
Vec3 tangent_of(const Vec3& n);

// Whether the triangle with corners v of patch `patch` lies inside a closed object (the
// floor under a block): from its centroid and from a twentieth of the way
// in from each corner, every one of 7 rays into its hemisphere (the normal
// and six at 60 degrees from it) meets the back of a face first. A triangle
// found shut at some of those points and open at others lies partly under
// something open at its sides (a one-sided table top over a floor) and is
// not inside.
bool inside_closed_object(const Scene& scene, const Visibility& vis, const std::array<Vec3, 3>& v, int patch);

// Per element of `el`: 1 where it emits and lies inside a closed object.
// Light emitted there goes into the object, and every method counts it as
// escaped power.
std::vector<char> emitting_inside_objects(const Scene& scene, const ElementSet& el, const Visibility& vis);

// One warning per emitting face with elements of `el` inside a closed object
// (`inside`, per element), naming the share of its area they cover.
std::vector<std::string> enclosed_emitter_warnings(const Scene& scene, const ElementSet& el,
                                                   const std::vector<char>& inside);

// Shadow rays of one pair: cast, or skipped because nothing can occlude.
struct RayCount {
  long long cast = 0, skipped = 0;
  long long unoccludable = 0;  // pairs whose rays were all skipped
  RayCount& operator+=(const RayCount& o) {
    cast += o.cast;
    skipped += o.skipped;
    unoccludable += o.unoccludable;
    return *this;
  }
};

// The visible fraction between two elements, from shadow rays between
// stratified points of both (the source strata visited in a shuffled order,
// so that receiver and source strata pair at random), cast only where the
// shaft test finds a patch that could be in the way (none at all in a convex
// enclosure: no Embree scene is then built). One random stream per pair,
// seeded from the pair's two ids in increasing order, so the answer does not
// depend on the thread that asks nor on which of the two is the receiver.
// Only rays between points that lie in front of each other's planes count
// (light passes only there); a pair none of whose rays does takes the
// fraction over all of them. So an element straddling the other's plane is
// not darkened by what blocks its back half.
// Each ray that counts is weighed by the point kernel between its ends
// (cos x cos / r^2, as the link's form factor weighs the pair's points), so
// the fraction is that of the transport, not of the point pairs: they
// differ where what is hidden sends more (or less) than what is seen, as
// where an occluder near the receiver hides a source's far part and not its
// near part (test TheFractionIsTheTransportsWhereAnOccluderHidesTheSourcesFarPart);
// the plain fraction lets power escape from a closed room lit by a lamp hung
// close in front of a wall (docs/decisions.md).
class VisibilityEstimator {
public:
  // `rays` is rounded up to a perfect square (the strata).
  VisibilityEstimator(const Scene& scene, int rays);
  ~VisibilityEstimator();
  VisibilityEstimator(const VisibilityEstimator&) = delete;
  VisibilityEstimator& operator=(const VisibilityEstimator&) = delete;

  // a, b: the two elements' triangles (a point is a triangle with three equal
  // corners), pa, pb their patches, id_a, id_b their ids for the stream.
  // Thread-safe; counts the rays in `count`. side x side rays (stratified
  // on both triangles); 0: the estimator's own count. The rays are cast
  // only where the shaft test says something may be in the way, unless
  // `test_shaft` is false (for pairs known to be near an occluder, where the
  // test almost never clears them and costs more than the rays).
  double visible_fraction(const Triangle& a, int pa, uint64_t id_a, const Triangle& b, int pb, uint64_t id_b,
                          RayCount& count, int side = 0, bool test_shaft = true) const;
  int side() const { return side_; }

  // Into seen[i]: whether the segment between x[i] (on a surface facing
  // nx[i]) and y[i] (on one facing ny[i]), its ends lifted off their
  // surfaces (Visibility::visible_off_surfaces_each), is clear of every
  // patch but pa[i] and pb[i] (always in a convex enclosure). One call to
  // Embree for all n. Thread-safe.
  void visible(const Vec3* x, const Vec3* nx, const Vec3* y, const Vec3* ny, const int* pa, const int* pb, size_t n,
               unsigned char* seen) const;

  // Embree's scene, built on the first call even in a convex enclosure
  // (where visible_fraction needs none). Thread-safe.
  const Visibility& rays() const;

  bool convex_enclosure() const;
  // Patches p and q can exchange light (Occlusion::facing).
  bool facing(int p, int q) const;
  // Lower bound of the distance from x to patch p.
  double distance_to_patch(int p, const Vec3& x) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int side_ = 4;
};

// Energy balance and residual of a solve, element by element: emitted
// E a = absorbed (1 - rho) H a + escaped B a (1 - sent row), and the
// residual max |E + rho H - B| / max |B| per channel, where H is the
// gathered irradiance, the row sum the element's total form factor (1 in a
// closed scene) and the sent row the fraction of B a the solve carries to
// other elements (the row sum again where form factors are reciprocal, as
// in the matrix method). Fills the power_* and residual fields of `stats`, and
// error_bound: the residual over 1 - max(rho x row sum), which bounds the
// error of B relative to max |B| (the Neumann series of rho F), or -1 when
// rho F has no norm below 1 and so gives no bound.
class BalanceAccumulator {
public:
  void add(double area, const Rgb& reflectance, const Rgb& emission, const Rgb& radiosity, const Rgb& gathered,
           double row_sum, double sent_row);
  void finish(SolveStats& stats) const;

private:
  Rgb emitted_{0.0}, absorbed_{0.0}, escaped_{0.0}, worst_{0.0}, largest_{0.0};
  Rgb contraction_{0.0};  // max over elements of rho x row sum: the norm of rho F
};

// The stopping rule of a Gauss-Seidel solve, and its acceleration. The
// change of one sweep says little about the error where the iteration
// contracts slowly: with reflectance 0.999 in a closed room each sweep takes
// off about 0.1% of the error, and a change of 1e-6 leaves an error near
// 1e-3. The monitor estimates the contraction q per sweep from successive
// changes. While q holds steady (the last three ratios within 1%), the error
// is one mode decaying by q per sweep: the error left is change x q / (1 - q)
// by the geometric series, and when that is above the tolerance the caller
// extrapolates the mode away (Aitken): B += q / (1 - q) (B - B_before).
// Otherwise the bound of the system itself holds: error <= change x k / (1 - k)
// with k = max(rho x row sum), the norm of rho F (`contraction`; 1 or more
// gives none, and then only a steady q can stop). A solve stops when the
// change and the error left are both within tolerance x the largest value.
class SweepMonitor {
public:
  enum class Action { go_on, extrapolate, stop };
  SweepMonitor(double tolerance, double contraction) : tolerance_(tolerance), contraction_(contraction) {}
  // After a sweep whose largest change was `change` and largest value `top`.
  Action after_sweep(double change, double top);
  // The factor q / (1 - q) to extrapolate with (after Action::extrapolate).
  double extrapolation_factor() const { return q_ / (1.0 - q_); }
  int extrapolations() const { return extrapolations_; }

private:
  bool steady();  // three ratios recorded and within 1% of each other (sets q_ to the largest)
  Action maybe_extrapolate();
  double tolerance_, contraction_;
  double previous_ = 0.0;            // change of the sweep before (0: none since a reset)
  std::array<double, 3> ratios_{};   // the last three change ratios
  int count_ = 0;                    // ratios recorded since the last reset
  double q_ = 0.0;
  int extrapolations_ = 0;
};

// Runs f in a TBB arena of `threads` workers (0 = all cores): the thread
// count is the call's own, never process-wide state.
void run_in_arena(int threads, const std::function<void()>& f);

// The skips every solver reports from its visibility counts (convex
// enclosure, unoccludable pairs), appended to stats.skips.
void report_visibility_skips(SolveStats& stats, const char* pair_kind);

}  // namespace radmesh
