// Private to io/ and bench/: PNG pictures of VTK render windows and charts.
// Built only with RADMESH_WITH_RENDERING. Includes VTK headers: never include
// it from a public header.
#pragma once

#include "io/writers/atomic_file.h"
#include "io/writers/vtk_file.h"

#include <vtkContextItem.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <ostream>
#include <string>

namespace radmesh::internal {

// Renders nothing itself: grabs what `window` shows (after its Render()) and
// writes it as a PNG to `path`, atomically. Throws IoError.
inline void write_window_png(vtkRenderWindow* window, const std::string& path) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputConnection(grab->GetOutputPort());
  writer->WriteToMemoryOn();
  run_vtk_writer(writer.Get(), path);
  vtkUnsignedCharArray* bytes = writer->GetResult();
  write_file_atomically(path, [bytes](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes->GetPointer(0)),
              static_cast<std::streamsize>(bytes->GetNumberOfValues()));
  });
}

// Renders a chart off screen on `display` (an XConnection's Display*) at
// width x height on white, and writes it as a PNG to `path`. Throws IoError.
inline void write_chart_png(vtkContextItem* chart, void* display, int width, int height, const std::string& path) {
  vtkNew<vtkRenderWindow> window;
  window->SetDisplayId(display);
  window->SetOffScreenRendering(1);
  window->SetSize(width, height);
  vtkNew<vtkContextView> view;
  view->SetRenderWindow(window);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  view->GetScene()->AddItem(chart);
  window->Render();
  write_window_png(window, path);
}

}  // namespace radmesh::internal
