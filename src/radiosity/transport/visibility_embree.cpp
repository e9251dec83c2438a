// The one file that talks to Embree.

#include "radiosity/transport/visibility.h"

#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radiosity/transport/sampling.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace radmesh {

namespace {

// An intersect context carrying the patches whose hits are ignored.
struct QueryContext {
  RTCIntersectContext base;  // must come first: Embree passes &base back to us
  const int* prim_patch;
  int ignore_a, ignore_b;
  const int* ignore_each;    // per ray (by its id), or null
  const int* ignore_each_b;  // a second per ray, or null
};

void ignore_filter(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = reinterpret_cast<const QueryContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    const int patch = ctx->prim_patch[prim];
    if (patch == ctx->ignore_a || patch == ctx->ignore_b ||
        (ctx->ignore_each && patch == ctx->ignore_each[RTCRayN_id(args->ray, args->N, i)]) ||
        (ctx->ignore_each_b && patch == ctx->ignore_each_b[RTCRayN_id(args->ray, args->N, i)]))
      args->valid[i] = 0;
  }
}

void on_embree_error(void*, RTCError code, const char* message) {
  // Embree's callback must not throw; failures surface through the checks in
  // the constructor (rtcGetDeviceError) instead.
  (void)code;
  (void)message;
}

}  // namespace

struct Visibility::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<int> prim_patch;
  // Embree traces in float: geometry and rays are stored relative to
  // `origin` and divided by the scene's largest extent, so that its
  // products of coordinates (a cross product dotted with a third vector: a
  // length cubed) stay far inside float's range whatever the scene's unit,
  // and so that a scene scaled by any factor or moved gives Embree the same
  // floats (up to the double rounding before, 2^-29 of a float step) and
  // the same hits.
  Vec3 origin{0.0};
  double scale = 1.0;
  double lift = 0.0;  // how far visible_off_surfaces lifts a segment's ends off their surfaces
  double reach = 0.0;         // of ray_end's rays: 4 x the scene's diagonal
  std::vector<Vec3> normals;  // per patch

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

Visibility::Visibility(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  const Mesh mesh = triangulate_patches(scene);
  Impl& m = *impl_;
  m.device = rtcNewDevice(nullptr);  // note: "threads=N" would cap TBB for the whole process
  if (!m.device) throw NumericalError("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(m.device, on_embree_error, nullptr);

  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const Vec3& p : mesh.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  m.origin = mesh.positions.empty() ? Vec3(0.0) : 0.5 * (lo + hi);
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  if (extent > 0.0 && std::isfinite(extent)) m.scale = 1.0 / extent;
  // About 17 float steps at the scene's edge: the lifted end lies off its
  // surface (and off a patch coinciding with it, as a two-sided panel's
  // back) in the float coordinates Embree traces in.
  m.lift = mesh.positions.empty() ? 0.0 : kLift * glm::length(hi - lo);
  m.reach = 4.0 * scene.diagonal();
  for (const Patch& p : scene.patches) m.normals.push_back(p.normal);

  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* verts = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
  if (!verts || !idx) throw NumericalError("Embree: cannot allocate geometry buffers");
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3 p = (mesh.positions[i] - m.origin) * m.scale;
    verts[3 * i] = static_cast<float>(p.x);
    verts[3 * i + 1] = static_cast<float>(p.y);
    verts[3 * i + 2] = static_cast<float>(p.z);
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) idx[3 * t + static_cast<size_t>(k)] = static_cast<unsigned>(mesh.triangles[t][static_cast<size_t>(k)]);
  m.prim_patch = mesh.patch;
  rtcCommitGeometry(geom);
  rtcAttachGeometry(m.scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(m.scene);
  const RTCError err = rtcGetDeviceError(m.device);
  if (err != RTC_ERROR_NONE)
    throw NumericalError("Embree: building the visibility scene failed (error " +
                         std::to_string(static_cast<int>(err)) + ")");
}

Visibility::~Visibility() = default;

namespace {

// A ray from `from` along `direction` over the parameter range [tnear,
// tfar], both taken to Embree's frame (relative to `origin`, times `scale`:
// the parameter keeps its meaning), and a context ignoring two patches.
RTCRay make_ray(const Vec3& from, const Vec3& origin, double scale, Vec3 direction, float tnear, float tfar) {
  const Vec3 o = (from - origin) * scale;
  direction *= scale;
  RTCRay ray;
  ray.org_x = static_cast<float>(o.x);
  ray.org_y = static_cast<float>(o.y);
  ray.org_z = static_cast<float>(o.z);
  ray.dir_x = static_cast<float>(direction.x);
  ray.dir_y = static_cast<float>(direction.y);
  ray.dir_z = static_cast<float>(direction.z);
  ray.tnear = tnear;
  ray.tfar = tfar;
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  return ray;
}

QueryContext make_context(const std::vector<int>& prim_patch, int ignore_a, int ignore_b) {
  QueryContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.base.filter = ignore_filter;
  ctx.prim_patch = prim_patch.data();
  ctx.ignore_a = ignore_a;
  ctx.ignore_b = ignore_b;
  ctx.ignore_each = nullptr;
  ctx.ignore_each_b = nullptr;
  return ctx;
}

}  // namespace

namespace {

// n rays traced into seen[i] (1: nothing hit), each made by ray(i), one by
// one: Embree's stream call (rtcOccluded1M) answered about 2 in 10^4
// random segments of the Cornell box otherwise than the same rays traced
// alone (grazing edges), and otherwise again for the box scaled by 1e-4,
// where every float it was given was the same.
template <class MakeRay>
void trace_rays(const RTCScene scene, QueryContext& ctx, size_t n, MakeRay&& ray, unsigned char* seen) {
  for (size_t i = 0; i < n; ++i) {
    RTCRay r = ray(i);
    r.id = static_cast<unsigned>(i);  // for a per-ray ignored patch
    rtcOccluded1(scene, &ctx.base, &r);
    seen[i] = r.tfar >= 0.0f ? 1 : 0;
  }
}

// Open segments (from[i], to[i]), the first and last 1e-6 of each left out.
void trace_segments(const RTCScene scene, const Vec3& origin, double scale, QueryContext& ctx, const Vec3* from,
                    const Vec3* to, size_t n, unsigned char* seen) {
  trace_rays(
      scene, ctx, n, [&](size_t i) { return make_ray(from[i], origin, scale, to[i] - from[i], 1e-6f, 1.0f - 1e-6f); }, seen);
}

}  // namespace

void Visibility::visible(const Vec3* from, const Vec3* to, size_t n, int ignore_a, int ignore_b, unsigned char* seen) const {
  QueryContext ctx = make_context(impl_->prim_patch, ignore_a, ignore_b);
  trace_segments(impl_->scene, impl_->origin, impl_->scale, ctx, from, to, n, seen);
}

void Visibility::visible_each(const Vec3* from, const Vec3* to, size_t n, int ignore_a, const int* ignore_each,
                              unsigned char* seen) const {
  QueryContext ctx = make_context(impl_->prim_patch, ignore_a, -1);
  ctx.ignore_each = ignore_each;
  trace_segments(impl_->scene, impl_->origin, impl_->scale, ctx, from, to, n, seen);
}

bool Visibility::visible_off_surfaces(const Vec3& from, const Vec3& from_normal, const Vec3& to, const Vec3& to_normal,
                                      int ignore_a, int ignore_b) const {
  unsigned char seen = 0;
  visible_off_surfaces(&from, from_normal, &to, to_normal, 1, ignore_a, ignore_b, &seen);
  return seen != 0;
}

void Visibility::visible_off_surfaces(const Vec3* from, const Vec3& from_normal, const Vec3* to, const Vec3& to_normal,
                                      size_t n, int ignore_a, int ignore_b, unsigned char* seen) const {
  const Impl& m = *impl_;
  QueryContext ctx = make_context(m.prim_patch, ignore_a, ignore_b);
  const Vec3 up_from = m.lift * from_normal, up_to = m.lift * to_normal;
  trace_rays(
      m.scene, ctx, n,
      [&](size_t i) {
        const Vec3 a = from[i] + up_from;
        return make_ray(a, m.origin, m.scale, to[i] + up_to - a, 0.0f, 1.0f);
      },
      seen);
}

void Visibility::visible_off_surfaces_each(const Vec3* from, const Vec3* from_normal, const Vec3* to,
                                           const Vec3* to_normal, const int* ignore_a, const int* ignore_b, size_t n,
                                           unsigned char* seen) const {
  const Impl& m = *impl_;
  QueryContext ctx = make_context(m.prim_patch, -1, -1);
  ctx.ignore_each = ignore_a;
  ctx.ignore_each_b = ignore_b;
  trace_rays(
      m.scene, ctx, n,
      [&](size_t i) {
        const Vec3 a = from[i] + m.lift * from_normal[i];
        return make_ray(a, m.origin, m.scale, to[i] + m.lift * to_normal[i] - a, 0.0f, 1.0f);
      },
      seen);
}

int Visibility::first_hit(const Vec3& from, const Vec3& direction, double reach, int ignore) const {
  const Impl& m = *impl_;
  QueryContext ctx = make_context(m.prim_patch, ignore, -1);
  RTCRayHit rh;
  // Not the surface the ray leaves (nor one lying on it).
  rh.ray = make_ray(from, m.origin, m.scale, direction, static_cast<float>(1e-7 * reach), static_cast<float>(reach));
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(m.scene, &ctx.base, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return -1;
  return m.prim_patch[rh.hit.primID];
}

Visibility::RayEnd Visibility::ray_end(const Vec3& x, const Vec3& d, int ignore) const {
  const int hit = first_hit(x, d, impl_->reach, ignore);
  if (hit < 0) return RayEnd::nowhere;
  return glm::dot(impl_->normals[static_cast<size_t>(hit)], d) < 0.0 ? RayEnd::front : RayEnd::back;
}

bool Visibility::enclosed(const Vec3& x, const Vec3& normal, int ignore, uint64_t seed) const {
  const CosineHemisphere h(normal);
  SplitMix rng(seed);
  constexpr int side = 8;
  static_assert(side * side == kEnclosureRays);
  for (int k = 0; k < kEnclosureRays; ++k)
    if (ray_end(x, h.direction(k, side, rng), ignore) != RayEnd::front) return false;
  return true;
}

}  // namespace radmesh
