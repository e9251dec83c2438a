// Progress reporting from the library: a callback, never printing.
#pragma once

#include <functional>
#include <string>

namespace radmesh {

// Called with the phase name and the fraction done in [0, 1]. May be empty.
// Called from the calling thread only, at least every second or so of work
// on scenes of up to a few hundred thousand elements. A callback may throw
// to stop the work: the exception leaves the library call that reported,
// which keeps nothing of it (the Python module stops on Ctrl-C this way).
using ProgressFn = std::function<void(const std::string& phase, double fraction)>;

}  // namespace radmesh
