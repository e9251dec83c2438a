// PNG picture of a solution through VTK's OpenGL renderer. VTK stays inside this file.
#include "radmesh/png_render.h"

#include "io/writers/atomic_file.h"
#include "io/render/vtk_render.h"
#include "io/render/x_display.h"
#include "radmesh/errors.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

namespace radmesh {
namespace {

constexpr double kViewAngleDegrees = 39.3;  // vertical field of view of the Cornell box camera
constexpr double kGamma = 2.2;             // display gamma of the tone map

void check_options(const RenderOptions& options) {
  if (options.width <= 0 || options.height <= 0) {
    throw InputError("render: width and height must be positive, got " +
                     std::to_string(options.width) + " x " + std::to_string(options.height));
  }
  if (!(options.white_percentile >= 0.0 && options.white_percentile <= 1.0)) {
    throw InputError("render: white_percentile must be in [0, 1], got " +
                     std::to_string(options.white_percentile));
  }
}

// Throws IoError naming `path` unless the nodal field matches the mesh and
// every triangle has a patch with a material (the tone map needs its emission).
void check_inputs(const std::string& path, const Scene& scene, const Mesh& mesh,
                  const NodalField& nodal) {
  const auto fail = [&path](const std::string& what) {
    throw IoError(path + ": " + what);
  };
  if (nodal.corners.size() != mesh.patch.size()) {
    fail("the nodal field has " + std::to_string(nodal.corners.size()) + " triangles, the mesh " +
         std::to_string(mesh.patch.size()));
  }
  if (nodal.radiosity.size() != nodal.points.size()) {
    fail("the nodal field has " + std::to_string(nodal.radiosity.size()) + " values for " +
         std::to_string(nodal.points.size()) + " points");
  }
  for (std::size_t t = 0; t < nodal.corners.size(); ++t) {
    const int p = mesh.patch[t];
    if (p < 0 || static_cast<std::size_t>(p) >= scene.patches.size() ||
        scene.patches[p].material < 0 ||
        static_cast<std::size_t>(scene.patches[p].material) >= scene.materials.size()) {
      fail("triangle " + std::to_string(t) + " has patch " + std::to_string(p) +
           " without a valid material");
    }
    for (const int v : nodal.corners[t]) {
      if (v < 0 || static_cast<std::size_t>(v) >= nodal.points.size()) {
        fail("triangle " + std::to_string(t) + " has display vertex index " + std::to_string(v) +
             " out of range [0, " + std::to_string(nodal.points.size()) + ")");
      }
    }
  }
}

// The tone map's white point: the `percentile` quantile (nearest rank) of the
// max-channel radiosity over the display vertices of non-emitting triangles.
// 1 when there is no such vertex or the quantile is not positive.
double white_point(const Scene& scene, const Mesh& mesh, const NodalField& nodal,
                   double percentile) {
  std::vector<char> counted(nodal.points.size(), 0);
  std::vector<double> values;
  for (std::size_t t = 0; t < nodal.corners.size(); ++t) {
    const Material& material = scene.materials[scene.patches[mesh.patch[t]].material];
    if (material.emission != Rgb(0.0)) continue;
    for (const int v : nodal.corners[t]) {
      if (counted[v]) continue;
      counted[v] = 1;
      const Rgb& b = nodal.radiosity[v];
      values.push_back(std::max({b.r, b.g, b.b}));
    }
  }
  if (values.empty()) return 1.0;
  const auto n = static_cast<double>(values.size());
  const double nearest_rank = std::clamp(std::ceil(percentile * n) - 1.0, 0.0, n - 1.0);
  const auto rank = static_cast<std::ptrdiff_t>(nearest_rank);
  std::nth_element(values.begin(), values.begin() + rank, values.end());
  const double white = values[static_cast<std::size_t>(rank)];
  return white > 0.0 ? white : 1.0;  // also catches NaN
}

// 8-bit colour of radiosity `b`: clamp((b / white)^(1/2.2), 0, 1) per channel
// (negative and NaN values show black).
void tone_map(const Rgb& b, double white, unsigned char rgb[3]) {
  for (int c = 0; c < 3; ++c) {
    const double x = b[c] > 0.0 ? std::pow(b[c] / white, 1.0 / kGamma) : 0.0;
    rgb[c] = static_cast<unsigned char>(x < 1.0 ? std::lround(255.0 * x) : 255);
  }
}

// The display mesh as polydata with the tone-mapped colour on every vertex.
vtkNew<vtkPolyData> coloured_polydata(const NodalField& nodal, double white) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkUnsignedCharArray> colours;
  colours->SetName("colour");
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(static_cast<vtkIdType>(nodal.points.size()));
  for (std::size_t i = 0; i < nodal.points.size(); ++i) {
    const Vec3& p = nodal.points[i];
    points->InsertNextPoint(p.x, p.y, p.z);
    unsigned char rgb[3];
    tone_map(nodal.radiosity[i], white, rgb);
    colours->SetTypedTuple(static_cast<vtkIdType>(i), rgb);
  }
  vtkNew<vtkCellArray> triangles;
  for (const auto& corners : nodal.corners) {
    const vtkIdType ids[3] = {corners[0], corners[1], corners[2]};
    triangles->InsertNextCell(3, ids);
  }
  vtkNew<vtkPolyData> polydata;
  polydata->SetPoints(points);
  polydata->SetPolys(triangles);
  polydata->GetPointData()->SetScalars(colours);
  return polydata;
}

// Cornell convention: y up, looking along +z, centred on the bounding box, and
// back from its z_min face just far enough that the whole face is in view and
// touches the picture's edges in its tighter direction.
void place_camera(vtkRenderer* renderer, const std::vector<Vec3>& points, double aspect) {
  Vec3 lo(std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::lowest());
  for (const Vec3& p : points) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (points.empty()) lo = hi = Vec3(0.0);
  const Vec3 centre = 0.5 * (lo + hi);
  double half_height = std::max(0.5 * (hi.y - lo.y), 0.5 * (hi.x - lo.x) / aspect);
  if (!(half_height > 0.0)) half_height = 1.0;  // a flat or empty box: any distance works
  const double distance =
      half_height / std::tan(0.5 * kViewAngleDegrees * std::numbers::pi / 180.0);

  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetViewAngle(kViewAngleDegrees);
  camera->SetViewUp(0.0, 1.0, 0.0);
  camera->SetPosition(centre.x, centre.y, lo.z - distance);
  camera->SetFocalPoint(centre.x, centre.y, centre.z);
  renderer->ResetCameraClippingRange();
}

}  // namespace

bool render_png(const std::string& path, const Scene& scene, const Mesh& mesh,
                const Solution& solution, const RenderOptions& options, std::string* why) {
  check_options(options);
  const NodalField& nodal = solution.nodal;
  check_inputs(path, scene, mesh, nodal);
  // Opened before any VTK rendering object (VTK aborts without a display) and
  // outlives the render window below, which borrows it.
  const internal::XConnection x;
  if (x.get() == nullptr) {
    if (why != nullptr) *why = internal::kNoDisplayReason;
    return false;
  }

  // Lighting off: the colour on screen is the tone-mapped radiosity itself.
  const double white = white_point(scene, mesh, nodal, options.white_percentile);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(coloured_polydata(nodal, white));
  mapper->ScalarVisibilityOn();
  mapper->SetScalarModeToUsePointData();
  mapper->SetColorModeToDirectScalars();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->LightingOff();
  // Triangles are counter-clockwise around their patch normal, which points into
  // the room: a wall facing the camera is a front face, the closing front wall is culled.
  actor->GetProperty()->BackfaceCullingOn();

  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->SetBackground(0.0, 0.0, 0.0);
  place_camera(renderer, nodal.points, static_cast<double>(options.width) / options.height);

  vtkNew<vtkRenderWindow> window;
  window->SetDisplayId(x.get());
  window->SetOffScreenRendering(1);
  window->SetSize(options.width, options.height);
  window->AddRenderer(renderer);
  window->Render();

  internal::write_window_png(window, path);
  return true;
}

}  // namespace radmesh
