// Log-log error-versus-time plot through VTK's charts, rendered off screen.
#include "bench/plot.h"

#include "io/writers/atomic_file.h"
#include "io/render/vtk_render.h"
#include "io/render/x_display.h"
#include "radmesh/errors.h"

#include <vtkAxis.h>
#include <vtkChart.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace radmesh::bench {
namespace {

constexpr int kWidth = 900;
constexpr int kHeight = 650;

// Line colours (the "tab10" palette), cycled; markers cycle too, so that two
// series that share a colour still differ.
constexpr std::array<std::array<unsigned char, 3>, 10> kColours{{{31, 119, 180},
                                                                  {255, 127, 14},
                                                                  {44, 160, 44},
                                                                  {214, 39, 40},
                                                                  {148, 103, 189},
                                                                  {140, 86, 75},
                                                                  {227, 119, 194},
                                                                  {127, 127, 127},
                                                                  {188, 189, 34},
                                                                  {23, 190, 207}}};
constexpr std::array<int, 5> kMarkers{vtkPlotPoints::CIRCLE, vtkPlotPoints::SQUARE,
                                      vtkPlotPoints::DIAMOND, vtkPlotPoints::CROSS,
                                      vtkPlotPoints::PLUS};

bool plottable(double v) { return std::isfinite(v) && v > 0.0; }

// The range [lo, hi] of the plotted values along one axis.
struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return lo > hi; }
};

// Two columns (time, error) with the series' plottable points, which also widen
// the extents; null when none.
vtkSmartPointer<vtkTable> series_table(const Series& s, Extent& x_extent, Extent& y_extent) {
  vtkNew<vtkDoubleArray> x;
  x->SetName("x");
  vtkNew<vtkDoubleArray> y;
  y->SetName(s.name.c_str());
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (!plottable(s.x[i]) || !plottable(s.y[i])) continue;
    x->InsertNextValue(s.x[i]);
    y->InsertNextValue(s.y[i]);
    x_extent.add(s.x[i]);
    y_extent.add(s.y[i]);
  }
  if (x->GetNumberOfTuples() == 0) return nullptr;
  auto table = vtkSmartPointer<vtkTable>::New();
  table->AddColumn(x);
  table->AddColumn(y);
  return table;
}

// A log axis over `extent`, widened on both sides so that the markers at the
// ends are not cut by the frame: by 4% of its span in decades, at least 0.1
// decade (which also gives a single value a range). VTK's own range would end
// exactly at the extreme points. An empty extent (nothing to plot) gets
// [0.1, 10], a valid log range.
void style_axis(vtkAxis* axis, const std::string& title, const Extent& extent) {
  axis->SetTitle(title);
  axis->SetLogScale(true);  // active only when the whole range is positive, which it is
  axis->SetBehavior(vtkAxis::FIXED);
  if (extent.empty()) {
    axis->SetUnscaledRange(0.1, 10.0);
  } else {
    const double pad = std::max(0.04 * std::log10(extent.hi / extent.lo), 0.1);
    const double factor = std::pow(10.0, pad);
    axis->SetUnscaledRange(extent.lo / factor, extent.hi * factor);
  }
  axis->GetTitleProperties()->SetFontSize(15);
  axis->GetTitleProperties()->BoldOn();
  axis->GetLabelProperties()->SetFontSize(13);
  axis->SetGridVisible(true);
}

}  // namespace

bool plot_error_vs_time(const std::string& path, const std::string& title, const std::string& y_label,
                        const std::vector<Series>& series, std::string* why, const std::string& x_label) {
  for (const Series& s : series) {
    if (s.x.size() != s.y.size()) {
      throw InputError("plot " + path + ": series \"" + s.name + "\" has " +
                       std::to_string(s.x.size()) + " times and " + std::to_string(s.y.size()) +
                       " errors");
    }
  }
  // Opened before any VTK rendering object (VTK aborts without a display) and
  // outlives the render window below, which borrows it.
  const internal::XConnection x;
  if (x.get() == nullptr) {
    if (why != nullptr) *why = internal::kNoDisplayReason;
    return false;
  }

  // The tables must outlive the render: the plots only reference them.
  std::vector<vtkSmartPointer<vtkTable>> tables;
  vtkNew<vtkChartXY> chart;
  chart->SetTitle(title);
  chart->GetTitleProperties()->SetFontSize(17);
  chart->GetTitleProperties()->BoldOn();
  std::size_t drawn = 0;
  Extent x_extent, y_extent;
  for (const Series& s : series) {
    vtkSmartPointer<vtkTable> table = series_table(s, x_extent, y_extent);
    if (table == nullptr) continue;
    tables.push_back(table);
    // A line through a single point would make VTK report an error: markers only.
    vtkPlot* line =
        chart->AddPlot(table->GetNumberOfRows() > 1 ? vtkChart::LINE : vtkChart::POINTS);
    line->SetInputData(table, 0, 1);
    line->SetLabel(s.name);
    const auto& rgb = kColours[drawn % kColours.size()];
    line->SetColor(rgb[0], rgb[1], rgb[2], 255);
    line->SetWidth(2.0f);
    if (auto* points = vtkPlotPoints::SafeDownCast(line)) {
      points->SetMarkerStyle(kMarkers[drawn % kMarkers.size()]);
      points->SetMarkerSize(9.0f);
    }
    ++drawn;
  }
  style_axis(chart->GetAxis(vtkAxis::BOTTOM), x_label, x_extent);
  style_axis(chart->GetAxis(vtkAxis::LEFT), y_label, y_extent);
  chart->SetShowLegend(drawn > 0);
  if (drawn == 0) {  // VTK draws neither axes nor plots then: say why the picture is empty
    chart->SetRenderEmpty(true);
    chart->SetTitle(title + "\n(nothing to plot: no point with positive time and error)");
  }
  chart->GetLegend()->GetLabelProperties()->SetFontSize(14);
  // Bottom left: error curves fall to the right, so that corner stays clearest.
  chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::LEFT);
  chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::BOTTOM);

  internal::write_chart_png(chart, x.get(), kWidth, kHeight, path);
  return true;
}

}  // namespace radmesh::bench
