// VTK output: what write_vtu / write_mesh_vtu write is read back by VTK's own
// reader field by field, failures leave no file, and render_png draws what the
// camera convention and the winding convention promise.
#include "radmesh/png_render.h"
#include "radmesh/vtk_writer.h"
#include "radmesh/errors.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace radmesh {
namespace {

namespace fs = std::filesystem;

// A unit square in z = 0 split along its diagonal into two triangles, each its
// own patch: patch 0 is a grey wall, patch 1 an emitter. Both face +z and are
// wound counter-clockwise around +z.
struct TwoTriangles {
  Scene scene;
  Mesh mesh;
  TriangleQuality quality;
  Solution solution;

  TwoTriangles() {
    scene.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    scene.materials.resize(2);
    scene.materials[0].name = "grey";
    scene.materials[0].reflectance = Rgb(0.7, 0.6, 0.5);
    scene.materials[1].name = "light";
    scene.materials[1].reflectance = Rgb(0.1, 0.2, 0.3);
    scene.materials[1].emission = Rgb(10, 20, 30);
    scene.patches.resize(2);
    scene.patches[0].material = 0;
    scene.patches[0].outer = {0, 1, 2};
    scene.patches[1].material = 1;
    scene.patches[1].outer = {0, 2, 3};
    for (Patch& p : scene.patches) p.normal = Vec3(0, 0, 1);

    mesh.positions = scene.vertices;
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.patch = {0, 1};

    // Right isosceles triangles: legs 1, hypotenuse sqrt(2), inradius (2 - sqrt(2)) / 2.
    const double aspect = std::sqrt(2.0) / (2.0 * std::sqrt(3.0) * (2.0 - std::sqrt(2.0)) / 2.0);
    quality.min_angle = {45.0, 45.0};
    quality.aspect_ratio = {aspect, aspect};

    solution.element = {Rgb(1, 2, 3), Rgb(4, 5, 6)};
    // The material changes across the diagonal, so the display mesh duplicates
    // its two vertices: 6 display vertices, each with its own value.
    NodalField& nodal = solution.nodal;
    nodal.source_vertex = {0, 1, 2, 0, 2, 3};
    for (int v : nodal.source_vertex) nodal.points.push_back(mesh.positions[v]);
    nodal.corners = {{0, 1, 2}, {3, 4, 5}};
    for (int i = 0; i < 6; ++i) nodal.radiosity.push_back(Rgb(0.5 * i, 0.25 + i, 7.0 - i));
  }
};

// A fresh directory per test, removed afterwards.
class VtkIo : public ::testing::Test {
protected:
  const radmesh::test::TempDir tmp;
  const fs::path dir = tmp.path();
};

vtkNew<vtkUnstructuredGrid> read_vtu(const fs::path& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkNew<vtkUnstructuredGrid> grid;
  grid->ShallowCopy(reader->GetOutput());
  return grid;
}

// The array `name` exists with `components` components and one tuple per point or cell.
vtkDataArray* field(vtkFieldData* data, const char* name, int components, vtkIdType tuples) {
  vtkDataArray* a = data->GetArray(name);
  EXPECT_NE(a, nullptr) << "missing array " << name;
  if (a == nullptr) return nullptr;
  EXPECT_EQ(a->GetNumberOfComponents(), components) << name;
  EXPECT_EQ(a->GetNumberOfTuples(), tuples) << name;
  return a;
}

void expect_rgb(vtkDataArray* a, vtkIdType i, const Rgb& expected) {
  ASSERT_NE(a, nullptr);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a->GetComponent(i, c), expected[c]) << a->GetName() << "[" << i << "][" << c << "]";
  }
}

// Cell fields both writers share, checked against the TwoTriangles scene.
void expect_mesh_cell_data(vtkCellData* cells, const TwoTriangles& s) {
  vtkDataArray* patch_id = field(cells, "patch_id", 1, 2);
  vtkDataArray* area = field(cells, "area", 1, 2);
  vtkDataArray* min_angle = field(cells, "min_angle", 1, 2);
  vtkDataArray* aspect_ratio = field(cells, "aspect_ratio", 1, 2);
  vtkDataArray* reflectance = field(cells, "reflectance", 3, 2);
  vtkDataArray* emission = field(cells, "emission", 3, 2);
  ASSERT_TRUE(patch_id && area && min_angle && aspect_ratio && reflectance && emission);
  EXPECT_EQ(patch_id->GetDataType(), VTK_INT);
  for (vtkIdType t = 0; t < 2; ++t) {
    EXPECT_EQ(patch_id->GetComponent(t, 0), static_cast<double>(t));
    EXPECT_DOUBLE_EQ(area->GetComponent(t, 0), 0.5);
    EXPECT_EQ(min_angle->GetComponent(t, 0), s.quality.min_angle[t]);
    EXPECT_EQ(aspect_ratio->GetComponent(t, 0), s.quality.aspect_ratio[t]);
    expect_rgb(reflectance, t, s.scene.materials[t].reflectance);
    expect_rgb(emission, t, s.scene.materials[t].emission);
  }
}

TEST_F(VtkIo, WriteVtuRoundTripsEveryField) {
  const TwoTriangles s;
  const fs::path path = dir / "solution.vtu";
  write_vtu(path.string(), s.scene, s.mesh, s.quality, s.solution);
  ASSERT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));

  auto grid = read_vtu(path);
  ASSERT_EQ(grid->GetNumberOfPoints(), 6);
  ASSERT_EQ(grid->GetNumberOfCells(), 2);
  EXPECT_EQ(grid->GetPoints()->GetDataType(), VTK_DOUBLE);
  for (vtkIdType i = 0; i < 6; ++i) {
    double p[3];
    grid->GetPoint(i, p);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(p[c], s.solution.nodal.points[i][c]);
  }
  for (vtkIdType t = 0; t < 2; ++t) {
    EXPECT_EQ(grid->GetCellType(t), VTK_TRIANGLE);
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(t, n, ids);
    ASSERT_EQ(n, 3);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(ids[k], s.solution.nodal.corners[t][k]);
  }

  vtkDataArray* nodal = field(grid->GetPointData(), "radiosity", 3, 6);
  for (vtkIdType i = 0; i < 6; ++i) expect_rgb(nodal, i, s.solution.nodal.radiosity[i]);
  vtkDataArray* element = field(grid->GetCellData(), "radiosity", 3, 2);
  for (vtkIdType t = 0; t < 2; ++t) expect_rgb(element, t, s.solution.element[t]);
  expect_mesh_cell_data(grid->GetCellData(), s);
}

TEST_F(VtkIo, WriteMeshVtuHasMeshFieldsOnly) {
  const TwoTriangles s;
  const fs::path path = dir / "mesh.vtu";
  write_mesh_vtu(path.string(), s.scene, s.mesh, s.quality);

  auto grid = read_vtu(path);
  ASSERT_EQ(grid->GetNumberOfPoints(), 4);  // welded Mesh::positions, not display vertices
  ASSERT_EQ(grid->GetNumberOfCells(), 2);
  EXPECT_EQ(grid->GetPointData()->GetNumberOfArrays(), 0);
  EXPECT_EQ(grid->GetCellData()->GetNumberOfArrays(), 6);
  EXPECT_EQ(grid->GetCellData()->GetArray("radiosity"), nullptr);
  expect_mesh_cell_data(grid->GetCellData(), s);
}

TEST_F(VtkIo, WriteIntoMissingDirectoryThrowsAndLeavesNoFile) {
  const TwoTriangles s;
  const fs::path path = dir / "no_such_directory" / "solution.vtu";
  try {
    write_vtu(path.string(), s.scene, s.mesh, s.quality, s.solution);
    FAIL() << "write_vtu into a missing directory did not throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_mesh_vtu(path.string(), s.scene, s.mesh, s.quality), IoError);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
}

TEST_F(VtkIo, FailedWriteKeepsTheExistingFile) {
  // Write an inconsistent solution over a good file: the good file survives.
  TwoTriangles s;
  const fs::path path = dir / "solution.vtu";
  write_vtu(path.string(), s.scene, s.mesh, s.quality, s.solution);
  const auto size = fs::file_size(path);
  s.quality.min_angle.pop_back();
  EXPECT_THROW(write_vtu(path.string(), s.scene, s.mesh, s.quality, s.solution), IoError);
  EXPECT_EQ(fs::file_size(path), size);
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
}

// One 2 x 2 square in z = 0, centred at (1, 1), with uniform radiosity, wound
// counter-clockwise around -z (facing the camera, which looks along +z) or,
// with `facing_camera` false, around +z.
struct Square {
  Scene scene;
  Mesh mesh;
  Solution solution;

  Square(bool facing_camera, const Rgb& radiosity) {
    scene.vertices = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    scene.materials.resize(1);
    scene.materials[0].reflectance = Rgb(0.5);
    scene.patches.resize(1);
    scene.patches[0].material = 0;
    scene.patches[0].outer =
        facing_camera ? std::vector<int>{0, 3, 2, 1} : std::vector<int>{0, 1, 2, 3};
    scene.patches[0].normal = Vec3(0, 0, facing_camera ? -1 : 1);
    mesh.positions = scene.vertices;
    mesh.triangles = facing_camera ? std::vector<std::array<int, 3>>{{0, 3, 2}, {0, 2, 1}}
                                   : std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 3}};
    mesh.patch = {0, 0};
    solution.element = {radiosity, radiosity};
    solution.nodal.points = mesh.positions;
    solution.nodal.source_vertex = {0, 1, 2, 3};
    solution.nodal.corners = mesh.triangles;
    solution.nodal.radiosity.assign(4, radiosity);
  }
};

// What a test needs of a rendered PNG, read back with VTK's reader.
struct Picture {
  int width = 0, height = 0;
  unsigned char centre[3] = {0, 0, 0};  // RGB of the centre pixel
};

Picture read_png(const fs::path& path) {
  Picture picture;
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  picture.width = dims[0];
  picture.height = dims[1];
  if (image->GetNumberOfScalarComponents() < 3 || dims[0] < 1 || dims[1] < 1) {
    ADD_FAILURE() << "unexpected PNG layout";
    return picture;
  }
  const auto* pixel =
      static_cast<const unsigned char*>(image->GetScalarPointer(dims[0] / 2, dims[1] / 2, 0));
  for (int c = 0; c < 3; ++c) picture.centre[c] = pixel[c];
  return picture;
}

TEST_F(VtkIo, RenderPngShowsTheToneMappedWallFacingTheCamera) {
  const Rgb radiosity(0.5, 0.25, 0.125);
  const Square square(/*facing_camera=*/true, radiosity);
  RenderOptions options;
  options.width = 160;  // not square, so a swapped width and height shows
  options.height = 120;
  const fs::path path = dir / "square.png";
  std::string why;
  if (!render_png(path.string(), square.scene, square.mesh, square.solution, options, &why)) {
    GTEST_SKIP() << why;
  }
  const Picture picture = read_png(path);

  EXPECT_EQ(picture.width, 160);
  EXPECT_EQ(picture.height, 120);
  // Uniform radiosity: white is 0.5 (the max channel), so the colour is
  // (B / 0.5)^(1/2.2) per channel. Lighting is off, so the pixel is exactly
  // that up to rounding.
  for (int c = 0; c < 3; ++c) {
    const double expected = 255.0 * std::pow(radiosity[c] / 0.5, 1.0 / 2.2);
    EXPECT_NEAR(picture.centre[c], expected, 2.0) << "channel " << c;
  }
}

TEST_F(VtkIo, RenderPngCullsAWallFacingAway) {
  const Square square(/*facing_camera=*/false, Rgb(1.0));
  RenderOptions options;
  options.width = 64;
  options.height = 64;
  const fs::path path = dir / "away.png";
  std::string why;
  if (!render_png(path.string(), square.scene, square.mesh, square.solution, options, &why)) {
    GTEST_SKIP() << why;
  }
  const Picture picture = read_png(path);

  // Nothing drawn: the centre shows the black background.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(picture.centre[c], 0) << "channel " << c;
}

TEST_F(VtkIo, RenderPngRejectsBadOptionsBeforeLookingForADisplay) {
  const Square square(true, Rgb(1.0));
  RenderOptions options;
  options.white_percentile = 1.5;
  std::string why;
  EXPECT_THROW(render_png((dir / "bad.png").string(), square.scene, square.mesh, square.solution,
                          options, &why),
               InputError);
  options = RenderOptions{};
  options.width = 0;
  EXPECT_THROW(render_png((dir / "bad.png").string(), square.scene, square.mesh, square.solution,
                          options, &why),
               InputError);
  EXPECT_FALSE(fs::exists(dir / "bad.png"));
}

}  // namespace
}  // namespace radmesh
