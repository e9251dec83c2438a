// Lambert's contour sums, written so that the compiler vectorizes the loop
// over items: no table, no branch, every select a blend. Compiled with
// -O3 -fno-math-errno -fno-trapping-math (which allow that) and
// -ffp-contract=off, so that the AVX-512, AVX2 and baseline clones (chosen
// at load time) round every operation alike and give identical results.

#include "radiosity/transport/lambert_kernel.h"

#include <algorithm>

namespace radmesh::internal {

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
    o[i] = lambert_edge(ax[i], ay[i], az[i], bx[i], by[i], bz[i], nx, ny, nz) +
           lambert_edge(bx[i], by[i], bz[i], cx[i], cy[i], cz[i], nx, ny, nz) +
           lambert_edge(cx[i], cy[i], cz[i], ax[i], ay[i], az[i], nx, ny, nz);
}

__attribute__((target_clones("avx512f", "avx2", "default"))) void lambert_point_sums(size_t count,
                                                                                    const LambertSources& s,
                                                                                    double px, double py, double pz,
                                                                                    double nx, double ny, double nz,
                                                                                    double* out, double* kind) {
  const LambertItems c = s.corners;  // the pointers in locals: loaded once
  const double *mx = s.mx, *my = s.my, *mz = s.mz;
  // The arrays never overlap (GCC does not take __restrict on locals as
  // proof, and more than ten run-time checks stop it vectorizing).
#pragma GCC ivdep
  for (size_t i = 0; i < count; ++i) {
    // (p - a) . m, the products summed x, y, then z, as glm::dot does.
    const double side = ((px - c.ax[i]) * mx[i] + (py - c.ay[i]) * my[i]) + (pz - c.az[i]) * mz[i];
    const double ax = c.ax[i] - px, ay = c.ay[i] - py, az = c.az[i] - pz;
    const double bx = c.bx[i] - px, by = c.by[i] - py, bz = c.bz[i] - pz;
    const double cx = c.cx[i] - px, cy = c.cy[i] - py, cz = c.cz[i] - pz;
    const double ha = (nx * ax + ny * ay) + nz * az;
    const double hb = (nx * bx + ny * by) + nz * bz;
    const double hc = (nx * cx + ny * cy) + nz * cz;
    out[i] = lambert_edge(ax, ay, az, bx, by, bz, nx, ny, nz) + lambert_edge(bx, by, bz, cx, cy, cz, nx, ny, nz) +
             lambert_edge(cx, cy, cz, ax, ay, az, nx, ny, nz);
    // Selects, not branches, so that the loop vectorizes (the heights are
    // finite: the lowest is >= 0 exactly when all three are).
    const double lowest = std::min(ha, std::min(hb, hc));
    const double seen = lowest >= 0.0 ? kSourceInFront : kSourceCrosses;
    kind[i] = side <= 0.0 ? kSourceBehind : seen;
  }
}

}  // namespace radmesh::internal
