// Lambert's contour sums, written so that the compiler vectorizes the loop
// over items: no table, no branch, every select a blend. Compiled with
// -O3 -fno-math-errno -fno-trapping-math (which allow that) and
// -ffp-contract=off, so that the AVX-512, AVX2 and baseline clones (chosen
// at load time) round every operation alike and give identical results.

#include "radiosity/lambert_kernel.h"

namespace radmesh::detail {

namespace {

// One edge (p, q), both relative to the point: the angle times the
// n-component of the unit normal of the edge's plane (0 for an edge seen
// end-on).
inline double edge(double px, double py, double pz, double qx, double qy, double qz, double nx, double ny, double nz) {
  const double cx = py * qz - pz * qy, cy = pz * qx - px * qz, cz = px * qy - py * qx;
  const double s = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double t = subtended_angle(s, px * qx + py * qy + pz * qz) * (nx * cx + ny * cy + nz * cz) / s;
  return s > 0.0 ? t : 0.0;
}

}  // namespace

__attribute__((target_clones("avx512f", "avx2", "default"))) void lambert_triangle_sums(size_t count,
                                                                                       const LambertItems& items,
                                                                                       double nx, double ny,
                                                                                       double nz, double* out) {
  const double* __restrict ax = items.ax;
  const double* __restrict ay = items.ay;
  const double* __restrict az = items.az;
  const double* __restrict bx = items.bx;
  const double* __restrict by = items.by;
  const double* __restrict bz = items.bz;
  const double* __restrict cx = items.cx;
  const double* __restrict cy = items.cy;
  const double* __restrict cz = items.cz;
  double* __restrict o = out;
  for (size_t i = 0; i < count; ++i)
    o[i] = edge(ax[i], ay[i], az[i], bx[i], by[i], bz[i], nx, ny, nz) +
           edge(bx[i], by[i], bz[i], cx[i], cy[i], cz[i], nx, ny, nz) +
           edge(cx[i], cy[i], cz[i], ax[i], ay[i], az[i], nx, ny, nz);
}

}  // namespace radmesh::detail
