// Progress reporting from the library: a callback, never printing.
#pragma once

#include <functional>
#include <string>

namespace radmesh {

// Called with the phase name and the fraction done in [0, 1]. May be empty.
// Called from the calling thread only.
using ProgressFn = std::function<void(const std::string& phase, double fraction)>;

}  // namespace radmesh
