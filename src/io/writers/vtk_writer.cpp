// VTK XML unstructured grid (.vtu) writers. VTK stays inside this file.
#include "radmesh/vtk_writer.h"

#include "io/writers/atomic_file.h"
#include "io/writers/vtk_file.h"
#include "radmesh/errors.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkSmartPointer.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace radmesh {
namespace {

// Throws IoError naming `path` unless `count` == `expected`: the writer's inputs
// come from different stages and must describe the same triangles.
void check_count(const std::string& path, const char* what, std::size_t count,
                 std::size_t expected) {
  if (count != expected) {
    throw IoError(path + ": " + what + " has " + std::to_string(count) +
                  " entries, expected " + std::to_string(expected));
  }
}

// VTK arrays over our own vectors instead of copies: a grid is written from
// vectors that outlive it, and the writer only reads them (1 = VTK never
// frees them). A pixmap run's display mesh has tens of millions of
// triangles, and each copy of a 3-component field would hold 24 bytes a
// triangle more at the peak.
static_assert(sizeof(Rgb) == 3 * sizeof(double) && sizeof(Vec3) == 3 * sizeof(double));
template <class Array, class T>
vtkNew<Array> view_array(const char* name, const T* values, std::size_t count, int components) {
  vtkNew<Array> array;
  array->SetName(name);
  array->SetNumberOfComponents(components);
  array->SetArray(const_cast<T*>(values), static_cast<vtkIdType>(count) * components, 1);
  return array;
}

// A named 3-component double array, one tuple per entry of `values`.
vtkNew<vtkDoubleArray> rgb_array(const char* name, const std::vector<Rgb>& values) {
  return view_array<vtkDoubleArray>(name, reinterpret_cast<const double*>(values.data()), values.size(), 3);
}

// A named 1-component double array.
vtkNew<vtkDoubleArray> scalar_array(const char* name, const std::vector<double>& values) {
  return view_array<vtkDoubleArray>(name, values.data(), values.size(), 1);
}

// A grid of VTK_TRIANGLE cells over `points` (double precision).
vtkNew<vtkUnstructuredGrid> triangle_grid(const std::string& path, const std::vector<Vec3>& points,
                                          const std::vector<std::array<int, 3>>& triangles) {
  vtkNew<vtkPoints> vtk_points;
  vtk_points->SetData(view_array<vtkDoubleArray>("Points", reinterpret_cast<const double*>(points.data()), points.size(), 3));

  vtkNew<vtkIdTypeArray> offsets;
  vtkNew<vtkIdTypeArray> connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(triangles.size() + 1));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(3 * triangles.size()));
  offsets->SetValue(0, 0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[t][k];
      if (v < 0 || static_cast<std::size_t>(v) >= points.size()) {
        throw IoError(path + ": triangle " + std::to_string(t) +
                      " has vertex index " + std::to_string(v) + " out of range [0, " +
                      std::to_string(points.size()) + ")");
      }
      connectivity->SetValue(static_cast<vtkIdType>(3 * t + k), v);
    }
    offsets->SetValue(static_cast<vtkIdType>(t + 1), static_cast<vtkIdType>(3 * (t + 1)));
  }
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);

  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(vtk_points);
  grid->SetCells(VTK_TRIANGLE, cells);
  return grid;
}

// Cell data both writers share, one value per Mesh triangle: patch_id, area,
// min_angle, aspect_ratio, and the patch material's reflectance and emission.
void add_mesh_cell_data(const std::string& path, vtkCellData* cell_data, const Scene& scene,
                        const Mesh& mesh, const TriangleQuality& quality) {
  const auto n = static_cast<std::size_t>(mesh.triangle_count());
  check_count(path, "Mesh::patch", mesh.patch.size(), n);
  check_count(path, "TriangleQuality::min_angle", quality.min_angle.size(), n);
  check_count(path, "TriangleQuality::aspect_ratio", quality.aspect_ratio.size(), n);

  // Filled in place: no copy of a cell array is held (a pixmap run's display
  // mesh has tens of millions of triangles).
  vtkNew<vtkIntArray> patch_id;
  patch_id->SetName("patch_id");
  patch_id->SetNumberOfValues(static_cast<vtkIdType>(n));
  vtkNew<vtkDoubleArray> area, reflectance, emission;
  area->SetName("area");
  area->SetNumberOfValues(static_cast<vtkIdType>(n));
  for (vtkDoubleArray* a : {reflectance.Get(), emission.Get()}) {
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(static_cast<vtkIdType>(n));
  }
  reflectance->SetName("reflectance");
  emission->SetName("emission");
  for (std::size_t t = 0; t < n; ++t) {
    const int p = mesh.patch[t];
    if (p < 0 || static_cast<std::size_t>(p) >= scene.patches.size() ||
        scene.patches[p].material < 0 ||
        static_cast<std::size_t>(scene.patches[p].material) >= scene.materials.size()) {
      throw IoError(path + ": triangle " + std::to_string(t) +
                    " has patch " + std::to_string(p) + " without a valid material");
    }
    const Material& material = scene.materials[scene.patches[p].material];
    const auto i = static_cast<vtkIdType>(t);
    patch_id->SetValue(i, p);
    area->SetValue(i, mesh.area(static_cast<int>(t)));
    const double rho[3] = {material.reflectance.r, material.reflectance.g, material.reflectance.b};
    const double e[3] = {material.emission.r, material.emission.g, material.emission.b};
    reflectance->SetTypedTuple(i, rho);
    emission->SetTypedTuple(i, e);
  }
  cell_data->AddArray(patch_id);
  cell_data->AddArray(area);
  cell_data->AddArray(scalar_array("min_angle", quality.min_angle));
  cell_data->AddArray(scalar_array("aspect_ratio", quality.aspect_ratio));
  cell_data->AddArray(reflectance);
  cell_data->AddArray(emission);
}

// Binary, LZ4-compressed .vtu (faster to write than zlib, for somewhat
// larger files: docs/decisions.md), written to a temporary file renamed
// into place.
void write_grid(const std::string& path, vtkUnstructuredGrid* grid) {
  vtkNew<internal::StreamXmlWriter<vtkXMLUnstructuredGridWriter>> writer;
  writer->SetInputData(grid);
  writer->SetDataModeToBinary();
  writer->SetCompressorTypeToLZ4();
  internal::write_xml_atomically(writer.Get(), path);
}

// Named integer cell arrays, one value per cell (n cells).
void add_int_cell_fields(const std::string& path, vtkCellData* data,
                         const std::vector<std::pair<std::string, std::vector<int>>>& fields, std::size_t n) {
  for (const auto& [name, values] : fields) {
    check_count(path, name.c_str(), values.size(), n);
    data->AddArray(view_array<vtkIntArray>(name.c_str(), values.data(), values.size(), 1));
  }
}

}  // namespace

void write_vtu(const std::string& path, const Result& result) {
  write_vtu(path, *result.scene, result.mesh, compute_quality(result.mesh), result.solution, result.cell_fields);
}

void write_pvd(const std::string& path, const std::vector<std::string>& files) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
    for (size_t i = 0; i < files.size(); ++i)
      out << "    <DataSet timestep=\"" << i << "\" part=\"0\" file=\"" << files[i] << "\"/>\n";
    out << "  </Collection>\n</VTKFile>\n";
  });
}

void write_vtu(const std::string& path, const Scene& scene, const Mesh& mesh,
               const TriangleQuality& quality, const Solution& solution,
               const std::vector<std::pair<std::string, std::vector<int>>>& int_cell_fields) {
  const NodalField& nodal = solution.nodal;
  const auto n = static_cast<std::size_t>(mesh.triangle_count());
  check_count(path, "Solution::element", solution.element.size(), n);
  check_count(path, "NodalField::corners", nodal.corners.size(), n);
  check_count(path, "NodalField::radiosity", nodal.radiosity.size(), nodal.points.size());

  // Cells are the display triangles: NodalField::corners[t] is Mesh triangle t
  // with its vertices duplicated where radiosity must not be averaged.
  auto grid = triangle_grid(path, nodal.points, nodal.corners);
  grid->GetPointData()->AddArray(rgb_array("radiosity", nodal.radiosity));
  grid->GetCellData()->AddArray(rgb_array("radiosity", solution.element));
  add_mesh_cell_data(path, grid->GetCellData(), scene, mesh, quality);
  add_int_cell_fields(path, grid->GetCellData(), int_cell_fields, n);
  write_grid(path, grid);
}

void write_discontinuities_vtu(const std::string& path, const std::vector<DiscontinuitySegment>& segments) {
  LineSet lines;
  std::vector<int> kind, event, emitter, patch, other;
  for (const DiscontinuitySegment& d : segments) {
    lines.segments.push_back({d.a, d.b});
    kind.push_back(d.kind);
    event.push_back(static_cast<int>(d.event));
    emitter.push_back(d.emitter);
    patch.push_back(d.patch);
    other.push_back(d.other);
  }
  lines.int_fields = {{"kind", kind}, {"event", event}, {"emitter", emitter}, {"patch_id", patch}, {"other_patch", other}};
  write_lines_vtu(path, lines);
}

void write_lines_vtu(const std::string& path, const LineSet& lines) {
  const size_t n = lines.segments.size();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> cells;
  for (const auto& [a, b] : lines.segments) {
    for (const Vec3& v : {a, b})
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw IoError(path + ": line segment " + std::to_string(cells->GetNumberOfCells()) + " has a non-finite end");
    const vtkIdType ids[2] = {points->InsertNextPoint(a.x, a.y, a.z), points->InsertNextPoint(b.x, b.y, b.z)};
    cells->InsertNextCell(2, ids);
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->SetCells(VTK_LINE, cells);
  add_int_cell_fields(path, grid->GetCellData(), lines.int_fields, n);
  for (const auto& [name, values] : lines.real_fields) {
    check_count(path, name.c_str(), values.size(), n);
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(values[i]))
        throw IoError(path + ": field '" + name + "' of segment " + std::to_string(i) + " is " + std::to_string(values[i]));
      a->InsertNextValue(values[i]);
    }
    grid->GetCellData()->AddArray(a);
  }
  write_grid(path, grid);
}

void write_mesh_vtu(const std::string& path, const Scene& scene, const Mesh& mesh,
                    const TriangleQuality& quality) {
  auto grid = triangle_grid(path, mesh.positions, mesh.triangles);
  add_mesh_cell_data(path, grid->GetCellData(), scene, mesh, quality);
  write_grid(path, grid);
}

namespace {

vtkSmartPointer<vtkUnstructuredGrid> read_grid(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw IoError(path + ": no such file");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || grid == nullptr || grid->GetNumberOfPoints() == 0)
    throw IoError(path + ": not a VTK XML unstructured grid (.vtu) with points");
  return grid;
}

vtkDataArray* int_cell_array(const std::string& path, vtkUnstructuredGrid* grid, const char* name) {
  vtkDataArray* a = grid->GetCellData()->GetArray(name);
  if (a == nullptr || a->GetNumberOfComponents() != 1 || a->GetNumberOfTuples() != grid->GetNumberOfCells())
    throw IoError(path + ": cell array '" + name + "' missing or of the wrong size");
  return a;
}

}  // namespace

Mesh read_mesh_vtu(const std::string& path) {
  auto grid = read_grid(path);
  vtkDataArray* patch = int_cell_array(path, grid, "patch_id");
  Mesh mesh;
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) {
    double p[3];
    grid->GetPoint(i, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw IoError(path + ": point " + std::to_string(i) + " is not finite");
    mesh.positions.emplace_back(p[0], p[1], p[2]);
  }
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(c, n, ids);
    if (grid->GetCellType(c) != VTK_TRIANGLE || n != 3)
      throw IoError(path + ": cell " + std::to_string(c) + " is not a triangle");
    const double pid = patch->GetTuple1(c);
    if (!(pid >= 0.0) || pid != std::floor(pid))
      throw IoError(path + ": cell " + std::to_string(c) + " has patch_id " + std::to_string(pid));
    mesh.triangles.push_back({static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2])});
    mesh.patch.push_back(static_cast<int>(pid));
  }
  return mesh;
}

std::vector<DiscontinuitySegment> read_discontinuities_vtu(const std::string& path) {
  auto grid = read_grid(path);
  vtkDataArray* kind = int_cell_array(path, grid, "kind");
  vtkDataArray* patch = int_cell_array(path, grid, "patch_id");
  vtkDataArray* other = int_cell_array(path, grid, "other_patch");
  vtkDataArray* emitter = int_cell_array(path, grid, "emitter");
  vtkDataArray* event = grid->GetCellData()->GetArray("event");
  std::vector<DiscontinuitySegment> out;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(c, n, ids);
    if (grid->GetCellType(c) != VTK_LINE || n != 2)
      throw IoError(path + ": cell " + std::to_string(c) + " is not a line");
    const double k = kind->GetTuple1(c);
    if (k != 0.0 && k != 1.0 && k != 2.0)
      throw IoError(path + ": cell " + std::to_string(c) + " has kind " + std::to_string(k));
    DiscontinuitySegment d;
    d.kind = static_cast<int>(k);
    d.event = event ? static_cast<VisualEvent>(static_cast<int>(event->GetTuple1(c))) : VisualEvent::contact;
    d.patch = static_cast<int>(patch->GetTuple1(c));
    d.other = static_cast<int>(other->GetTuple1(c));
    d.emitter = static_cast<int>(emitter->GetTuple1(c));
    double a[3], b[3];
    grid->GetPoint(ids[0], a);
    grid->GetPoint(ids[1], b);
    d.a = Vec3(a[0], a[1], a[2]);
    d.b = Vec3(b[0], b[1], b[2]);
    out.push_back(d);
  }
  return out;
}

}  // namespace radmesh
