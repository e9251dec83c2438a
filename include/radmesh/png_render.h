// PNG picture of a solution through VTK's renderer (needs an X display).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"

#include <string>

namespace radmesh {

struct RenderOptions {
  // Picture size in pixels, each > 0.
  int width = 800;
  int height = 800;
  // Tone map: colour = clamp((B / white)^(1/2.2), 0, 1) per channel, where
  // white = the `white_percentile` quantile (nearest rank) of the max-channel
  // radiosity over the display vertices of triangles whose material has zero
  // emission, so emitters saturate and walls are well exposed. white = 1 when
  // there is no such vertex or the quantile is not positive. In [0, 1].
  double white_percentile = 0.99;
};

// Renders the nodal radiosity with lighting off (radiosity is the colour) on
// a black background, back faces culled (triangles are counter-clockwise
// around their patch normal, so a closing front wall facing into the room is
// not in the way), with the Cornell camera convention: y up, looking along +z
// from in front of the bounding box of the display vertices (z < z_min),
// centred on it, a 39.3 degree vertical field of view, and just far enough
// back that the whole z_min face is in view and touches the picture's edges
// in its tighter direction (+x is on the picture's left).
// Returns false (and sets *why, when not null) when no X display can be
// opened: the caller says so and goes on. The PNG is written through a
// temporary file like write_vtu. Throws InputError for out-of-range options,
// IoError when writing fails or the nodal field does not match the mesh.
bool render_png(const std::string& path, const Scene& scene, const Mesh& mesh,
                const Solution& solution, const RenderOptions& options, std::string* why);

}  // namespace radmesh
