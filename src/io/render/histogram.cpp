// Histograms as PNG pictures (radmesh quality's angle and aspect-ratio
// plots) through VTK's charts and an X display.

#include "radmesh/histogram.h"

#include "io/render/vtk_render.h"
#include "io/render/x_display.h"

#include <vtkAxis.h>
#include <vtkChart.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPlot.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>

namespace radmesh {

bool plot_histogram(const std::string& path, const std::string& title, const std::string& x_label,
                    const std::vector<double>& values, int bins, std::string* why) {
  const internal::XConnection x;  // before any VTK rendering object: VTK aborts without a display
  if (x.get() == nullptr) {
    if (why != nullptr) *why = internal::kNoDisplayReason;
    return false;
  }
  double lo = INFINITY, hi = -INFINITY;
  for (double v : values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  bins = std::max(bins, 1);
  if (!(lo <= hi)) lo = hi = 0.0;
  const double width = hi > lo ? (hi - lo) / bins : 1.0;
  std::vector<double> count(static_cast<size_t>(bins), 0.0);
  for (double v : values)
    if (std::isfinite(v))
      ++count[static_cast<size_t>(std::clamp(static_cast<int>((v - lo) / width), 0, bins - 1))];

  vtkNew<vtkTable> table;
  vtkNew<vtkDoubleArray> centre, number;
  centre->SetName(x_label.c_str());
  number->SetName("triangles");
  for (int b = 0; b < bins; ++b) {
    centre->InsertNextValue(lo + (b + 0.5) * width);
    number->InsertNextValue(count[static_cast<size_t>(b)]);
  }
  table->AddColumn(centre);
  table->AddColumn(number);

  vtkNew<vtkChartXY> chart;
  chart->SetTitle(title);
  chart->GetTitleProperties()->SetFontSize(17);
  vtkPlot* bars = chart->AddPlot(vtkChart::BAR);
  bars->SetInputData(table, 0, 1);
  bars->SetColor(31, 119, 180, 255);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(x_label);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle("triangles");

  internal::write_chart_png(chart, x.get(), 800, 500, path);
  return true;
}

}  // namespace radmesh
