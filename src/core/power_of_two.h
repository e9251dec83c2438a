// Units that are powers of two: dividing by one changes no digit, so data
// kept in float in such a unit (the pixmap method's texels, the
// hierarchical method's sending weights) stays inside float's
// range whatever the scene's unit or emission, and a scene at a size where
// that range was never in question gives the same bits.
#pragma once

#include <cmath>

namespace radmesh::internal {

// The power of two 2^e with x in [2^(e-1), 2^e); 1 for an x that is not
// finite and positive.
inline double power_of_two_above(double x) {
  if (!(x > 0.0) || !std::isfinite(x)) return 1.0;
  int exponent = 0;
  std::frexp(x, &exponent);
  return std::ldexp(1.0, exponent);
}

}  // namespace radmesh::internal
