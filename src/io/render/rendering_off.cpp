// Built instead of the VTK renderer when RADMESH_WITH_RENDERING is OFF: the
// pictures are not drawn, and the caller is told why (as without a display).

#include "radmesh/histogram.h"
#include "radmesh/png_render.h"

namespace radmesh {

namespace {
constexpr const char* kNoRendering = "radmesh was built without rendering (RADMESH_WITH_RENDERING=OFF)";
}

bool render_png(const std::string&, const Scene&, const Mesh&, const Solution&, const RenderOptions&,
                std::string* why) {
  if (why) *why = kNoRendering;
  return false;
}

bool plot_histogram(const std::string&, const std::string&, const std::string&, const std::vector<double>&, int,
                    std::string* why) {
  if (why) *why = kNoRendering;
  return false;
}

}  // namespace radmesh
