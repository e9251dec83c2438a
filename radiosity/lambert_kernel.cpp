// Lambert's contour sums, written so that the compiler vectorizes the loop
// over items: no table, no branch, every select a blend. Compiled with
// -O3 -fno-math-errno -fno-trapping-math (which allow that) and
// -ffp-contract=off, so that the AVX-512, AVX2 and baseline clones (chosen
// at load time) round every operation alike and give identical results.

#include "radiosity/lambert_kernel.h"

namespace radmesh::detail {

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

}  // namespace radmesh::detail
