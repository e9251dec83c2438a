// The radmesh program end to end: outputs on success, one-line errors and no
// output on bad input.

#include "io/writers/pixmap_io.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkCellType.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <iterator>
#include <nlohmann/json.hpp>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
namespace test = radmesh::test;

namespace {
using radmesh::test::kData;
const std::string kExe = RADMESH_EXE;

struct Result {
  int status;
  std::string err;
};

// Runs radmesh with `args`; captures stderr (in a folder of its own). A
// status of 128 + N: killed by signal N.
//
// With a `file_limit` >= 0, no file it writes may grow past that many bytes
// (RLIMIT_FSIZE: a write past it fails with EFBIG, as one on a full disk
// fails with ENOSPC); SIGXFSZ keeps its default action (the program must
// not be killed by it), and glibc fills what the program allocates with a
// pattern (no thread cache, MALLOC_PERTURB_), so that reading memory never
// set (VTK's XML writer freed such a pointer on a failed write) fails every
// time.
Result run_cli(const std::string& args, long file_limit = -1) {
  const test::TempDir tmp("stderr");
  const fs::path err = tmp / "stderr.txt";
  const std::string cmd = std::string("DISPLAY= ") +
                          (file_limit >= 0 ? "GLIBC_TUNABLES=glibc.malloc.tcache_count=0 MALLOC_PERTURB_=165 " : "") +
                          "exec " + kExe + " " + args + " >/dev/null 2>" + err.string();
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (file_limit >= 0) {
      const rlimit r{static_cast<rlim_t>(file_limit), static_cast<rlim_t>(file_limit)};
      ::setrlimit(RLIMIT_FSIZE, &r);
    }
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return {WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status), text};
}

// The summary.json a run wrote into `out`.
nlohmann::json read_summary(const fs::path& out) {
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
}
}  // namespace

TEST(Cli, RunWritesVtuSummaryAndProbes) {
  const test::TempDir tmp;
  const fs::path out = tmp / "plates";
  const fs::path probes = out.string() + "_probes.txt";
  {
    std::ofstream p(probes);
    p << "# label x y z nx ny nz\ncentre,top 0.5 0.5 1 0 0 -1\n";  // a comma: quoted in the CSV
  }
  const Result r = run_cli("run " + kData + "/parallel_plates/parallel_plates.obj -o " + out.string() +
                           " --method matrix --max-edge 0.25 --probe " + probes.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "radiosity.vtu"));
  EXPECT_TRUE(fs::exists(out / "probes.csv"));
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["counts"]["patches"], 2);
  EXPECT_EQ(s["solver"]["convex_enclosure"], true);
  EXPECT_EQ(s["counts"]["rays_cast"], 0);
  // The receiver's mean radiosity is rho * F = 0.5 * 0.199825 (Howell C-11):
  // the elements' mean to 1e-5; the mean of the field (exact at the vertices,
  // linear between them on 0.25 elements) within its interpolation error.
  for (const auto& p : s["patches"]) {
    if (p["name"] == "receiver") {
      EXPECT_NEAR(p["element_mean_radiosity"][0].get<double>(), 0.0999125, 1e-5);
      EXPECT_NEAR(p["mean_radiosity"][0].get<double>(), 0.0999125, 1e-2 * 0.0999125);
    }
  }
  // At the centre the point form factor between parallel unit squares 1 apart
  // is 4 * (corner form factor of a 0.5 x 0.5 rectangle at distance 1).
  std::ifstream csv(out / "probes.csv");
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_EQ(header, "label,x,y,z,nx,ny,nz,patch,r,g,b");
  EXPECT_EQ(row.substr(0, 13), "\"centre,top\",") << row;
  const double r_value = std::stod(row.substr(row.rfind(',', row.rfind(',', row.rfind(',') - 1) - 1) + 1));
  const double A = 0.5, c = 1.0, a = A / c;
  const double corner = 2 * (a / std::sqrt(1 + a * a) * std::atan(a / std::sqrt(1 + a * a))) / (2 * M_PI);
  EXPECT_NEAR(r_value, 0.5 * 4 * corner, 1e-9) << row;
  EXPECT_NE(r.err.find("PNG skipped"), std::string::npos) << r.err;  // no display here
}

TEST(Cli, AnMgfSceneIsCutToTheCurveToleranceAndItsNotesReachTheSummary) {
  const test::TempDir tmp;
  const fs::path scene = tmp / "ball.mgf";
  std::ofstream(scene) << "v c =\n p 0 0 0\nm lamp =\n ed 179\n sides 1\nsph c 1\n";
  const fs::path out = tmp / "ball";
  const Result r = run_cli("mesh " + scene.string() + " --curve-tolerance 0.1 -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["counts"]["patches"], 50);  // 10 x 5 faces at 0.1
  const std::string warnings = s["warnings"].dump();
  EXPECT_NE(warnings.find("within curve_tolerance 0.1"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("179 lm/W"), std::string::npos) << warnings;
  const Result bad = run_cli("mesh " + scene.string() + " --curve-tolerance 0.7 -o " + out.string());
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("--curve-tolerance 0.7"), std::string::npos) << bad.err;
}

TEST(Cli, DefaultMethodIsHierarchicalAndMatchesHowellOnThePlates) {
  const test::TempDir tmp;
  const fs::path out = tmp / "plates_default";
  const Result r = run_cli("run " + kData + "/parallel_plates/parallel_plates.obj --no-png -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["solver"]["method"], "hierarchical");
  EXPECT_EQ(s["counts"]["rays_cast"], 0);  // nothing can occlude: no shadow ray,
  EXPECT_GT(s["counts"]["rays_skipped"].get<long long>(), 0);  // and the summary says so
  EXPECT_GT(s["counts"]["pairs_unoccludable"].get<long long>(), 0);
  int receivers = 0;
  for (const auto& p : s["patches"])
    if (p["name"] == "receiver") {
      EXPECT_NEAR(p["element_mean_radiosity"][0].get<double>(), 0.0999125, 1e-5);  // rho * F, Howell C-11
      EXPECT_NEAR(p["mean_radiosity"][0].get<double>(), 0.0999125, 1e-2 * 0.0999125);  // the field's
      ++receivers;
    }
  EXPECT_EQ(receivers, 1);
}

TEST(Cli, APresetFillsInTheOptionsNotGivenAndTheSummarySaysWhich) {
  // --preset draft is --epsilon 0.01 (Method::presets); an option given by
  // name wins over it; a method without that preset, or a preset that is
  // none, is refused naming it.
  const test::TempDir tmp;
  const std::string plates = kData + "/parallel_plates/parallel_plates.obj --no-png -q -o ";
  const Result draft = run_cli("run " + plates + (tmp / "draft").string() + " --preset draft");
  ASSERT_EQ(draft.status, 0) << draft.err;
  const nlohmann::json s = read_summary(tmp / "draft");
  EXPECT_EQ(s["options"]["preset"], "draft");
  EXPECT_EQ(s["solver"]["epsilon"].get<double>(), 0.01);
  const Result given = run_cli("run " + plates + (tmp / "given").string() + " --preset draft --epsilon 0.005");
  ASSERT_EQ(given.status, 0) << given.err;
  EXPECT_EQ(read_summary(tmp / "given")["solver"]["epsilon"].get<double>(), 0.005);
  const Result plain = run_cli("run " + plates + (tmp / "plain").string());
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(read_summary(tmp / "plain")["options"]["preset"], "default");
  const Result matrix = run_cli("run " + plates + (tmp / "matrix").string() + " --preset fine --method matrix");
  EXPECT_EQ(matrix.status, 1);
  EXPECT_TRUE(test::contains(matrix.err, "--preset fine: --method matrix has none")) << matrix.err;
  EXPECT_FALSE(fs::exists(tmp / "matrix" / "summary.json"));
  const Result none = run_cli("run " + plates + (tmp / "none").string() + " --preset huge");
  EXPECT_NE(none.status, 0);
  EXPECT_TRUE(test::contains(none.err, "huge")) << none.err;
}

TEST(Cli, MeshWritesMeshAndSummary) {
  const test::TempDir tmp;
  const fs::path out = tmp / "mesh";
  const Result r =
      run_cli("mesh " + kData + "/cornell_box/cornell_box.obj --discontinuity contacts -o " + out.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "mesh.vtu"));
  EXPECT_TRUE(fs::exists(out / "discontinuities.vtu"));  // the blocks' contact outlines
  const nlohmann::json s = read_summary(out);
  EXPECT_GE(s["mesh_quality"]["min_angle_min"].get<double>(), 20.0 - 1e-6);
  EXPECT_EQ(r.err, "");  // --quiet
}

TEST(Cli, QualityOfAHierarchicalResultCountsZeroAreaTrianglesApart) {
  const test::TempDir tmp;
  const fs::path out = tmp / "quality_hier";
  ASSERT_EQ(run_cli("run " + kData + "/box_on_floor/box_on_floor.obj --no-png -q -o " + out.string()).status, 0);
  const nlohmann::json s = read_summary(out);
  const int zero = s["solver"]["zero_area_triangles"].get<int>();
  ASSERT_GT(zero, 0);
  const Result r = run_cli("quality " + (out / "radiosity.vtu").string() + " -q -o " + (out / "q").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream csv(out / "q" / "quality.csv");
  std::string line, total;
  while (std::getline(csv, line))
    if (line.rfind("-1,", 0) == 0) total = line;
  ASSERT_FALSE(total.empty());
  std::vector<std::string> f;
  std::stringstream ss(total);
  for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
  ASSERT_EQ(f.size(), 12u) << total;
  // patch_id,name,triangles,min_angle,max_angle,aspect_p50,aspect_p95,aspect_max,...,zero_area
  EXPECT_EQ(std::stoi(f[11]), zero);  // every fan triangle found, from the geometry alone
  EXPECT_EQ(std::stoi(f[2]), s["solver"]["leaves"].get<int>() + zero);
  EXPECT_GT(std::stod(f[3]), 10.0);   // the leaves' angles: halving keeps the roots' shapes
  EXPECT_LT(std::stod(f[4]), 170.0);
  EXPECT_LT(std::stod(f[7]), 100.0);  // no near-degenerate fan triangle among the aspect ratios
  // The radiosity.vtu cells: finite angles and aspect ratios, fans at 0, 180 and 0.
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName((out / "radiosity.vtu").string().c_str());
  reader->Update();
  vtkDataArray* aspect = reader->GetOutput()->GetCellData()->GetArray("aspect_ratio");
  vtkDataArray* flag = reader->GetOutput()->GetCellData()->GetArray("zero_area");
  ASSERT_TRUE(aspect && flag);
  for (vtkIdType c = 0; c < aspect->GetNumberOfTuples(); ++c) {
    EXPECT_TRUE(std::isfinite(aspect->GetTuple1(c)));
    EXPECT_EQ(aspect->GetTuple1(c) == 0.0, flag->GetTuple1(c) != 0.0) << "cell " << c;
  }
}

TEST(Cli, MeshDefaultsToFullDiscontinuityLines) {
  const test::TempDir tmp;
  // mesh has no method: its default is full (shadow lines), as for run --method matrix.
  const fs::path out = tmp / "mesh_default";
  const Result r = run_cli("mesh " + kData + "/box_on_floor/box_on_floor.obj -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["options"]["discontinuity"], "full");
  EXPECT_GT(s["counts"]["shadow_segments"].get<int>(), 0);
}

TEST(Cli, RunWithShadowLinesReportsThemAndWhatWasSkipped) {
  const test::TempDir tmp;
  const fs::path out = tmp / "run_full";
  const Result r = run_cli("run " + kData + "/box_on_floor/box_on_floor.obj --discontinuity full --max-edge 0.5 "
                           "--no-png -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["options"]["discontinuity"], "full");
  EXPECT_EQ(s["counts"]["contact_segments"], 4);
  EXPECT_EQ(s["counts"]["rounding_crossings"], 0);
  const auto& sh = s["shadow_lines"];
  EXPECT_GT(sh["d1_segments"].get<int>(), 0);
  EXPECT_EQ(sh["d2_segments"], 0);  // every box edge is parallel to a light edge
  EXPECT_EQ(s["counts"]["shadow_segments"].get<int>(), sh["d1_segments"].get<int>());
  EXPECT_EQ(sh["back_facing_pairs_skipped"], 4);  // the box's sides face away from the light
  EXPECT_NE(sh["left_out"].get<std::string>().find("EEE"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "discontinuities.vtu"));
}

TEST(Cli, ManyPatchesGoToPatchesCsvAndObjectsStayInTheSummary) {
  const test::TempDir tmp;
  // 10082 triangles (over kSummaryPatches): summary.json groups them by
  // object and names patches.csv, which has one row per patch.
  const fs::path out = tmp / "many_patches", dir = tmp / "many_patches_scene";
  fs::create_directories(dir);
  {
    std::ofstream(dir / "grid.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
    std::ofstream obj(dir / "grid.obj");
    obj << "mtllib grid.mtl\n";
    const int n = 71;  // n x n squares of a flat ground, two triangles each
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) obj << "v " << i << " 0 " << j << "\n";
    obj << "o ground\nusemtl grey\n";
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
        obj << "f " << a << ' ' << d << ' ' << c << "\nf " << a << ' ' << c << ' ' << b << "\n";
      }
  }
  const Result r = run_cli("mesh " + (dir / "grid.obj").string() + " --max-edge 1000 -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_FALSE(s.contains("patches"));
  EXPECT_EQ(s["patches_csv"], "patches.csv");
  ASSERT_EQ(s["objects"].size(), 1u);
  EXPECT_EQ(s["objects"][0]["name"], "ground");
  EXPECT_EQ(s["objects"][0]["patches"], 71 * 71 * 2);
  std::ifstream csv(out / "patches.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "id,name,material,area");
  int rows = 0;
  double area = 0.0;
  while (std::getline(csv, line)) {
    ++rows;
    area += std::stod(line.substr(line.rfind(',') + 1));
  }
  EXPECT_EQ(rows, 71 * 71 * 2);
  EXPECT_NEAR(area, s["objects"][0]["area"].get<double>(), 1e-9 * area);
}

TEST(Cli, HierarchicalRunWritesTheRefinementSeriesWithZeroAreaFlags) {
  const test::TempDir tmp;
  const fs::path out = tmp / "run_hier";
  const Result r = run_cli("run " + kData + "/box_on_floor/box_on_floor.obj --method hierarchical --epsilon 0.01 "
                           "--export-links --no-png -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  EXPECT_EQ(s["solver"]["method"], "hierarchical");
  EXPECT_EQ(s["options"]["discontinuity"], "contacts");  // the hierarchical default
  const int rounds = s["solver"]["rounds"].get<int>();
  EXPECT_GE(rounds, 2);
  EXPECT_EQ(s["solver"]["links_per_round"].size(), static_cast<size_t>(rounds));
  EXPECT_LT(std::abs(s["energy"]["relative_imbalance"][0].get<double>()), 0.02);
  // The series: one file per round, each present.
  std::ifstream pvd(out / "radiosity.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  for (int k = 0; k < rounds; ++k) {
    const std::string name = "radiosity_round_" + std::to_string(k) + ".vtu";
    EXPECT_NE(text.find(name), std::string::npos) << name;
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  // The final file flags its zero-area triangles, as many as the summary says.
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName((out / "radiosity.vtu").string().c_str());
  reader->Update();
  vtkDataArray* zero = reader->GetOutput()->GetCellData()->GetArray("zero_area");
  vtkDataArray* level = reader->GetOutput()->GetCellData()->GetArray("level");
  vtkDataArray* links = reader->GetOutput()->GetCellData()->GetArray("links");
  ASSERT_NE(zero, nullptr);
  ASSERT_NE(level, nullptr);
  ASSERT_NE(links, nullptr);
  int flagged = 0;
  for (vtkIdType c = 0; c < zero->GetNumberOfTuples(); ++c) flagged += zero->GetTuple1(c) != 0.0 ? 1 : 0;
  EXPECT_EQ(flagged, s["solver"]["zero_area_triangles"].get<int>());
  EXPECT_EQ(reader->GetOutput()->GetNumberOfCells(),
            s["solver"]["leaves"].get<int>() + s["solver"]["zero_area_triangles"].get<int>());
  // --export-links: one line per link, as many as the summary counts, and
  // per leaf as many as its `links` cell value says it gathers over.
  vtkNew<vtkXMLUnstructuredGridReader> lr;
  lr->SetFileName((out / "links.vtu").string().c_str());
  lr->Update();
  vtkUnstructuredGrid* lg = lr->GetOutput();
  ASSERT_EQ(lg->GetNumberOfCells(), s["solver"]["links"].get<vtkIdType>());
  vtkDataArray* ff = lg->GetCellData()->GetArray("form_factor");
  vtkDataArray* vis = lg->GetCellData()->GetArray("visible");
  vtkDataArray* rl = lg->GetCellData()->GetArray("receiver_level");
  vtkDataArray* rp = lg->GetCellData()->GetArray("receiver_patch");
  vtkDataArray* sp = lg->GetCellData()->GetArray("source_patch");
  ASSERT_TRUE(ff && vis && rl && rp && sp && lg->GetCellData()->GetArray("transport"));
  int partial = 0, hidden = 0;
  for (vtkIdType c = 0; c < lg->GetNumberOfCells(); ++c) {
    EXPECT_EQ(lg->GetCellType(c), VTK_LINE);
    EXPECT_GE(vis->GetTuple1(c), 0.0);
    EXPECT_LE(vis->GetTuple1(c), 1.0);
    EXPECT_LE(ff->GetTuple1(c), 1.0);
    EXPECT_EQ(ff->GetTuple1(c) > 0.0, vis->GetTuple1(c) > 0.0);  // only a hidden link carries nothing
    if (rp->GetTuple1(c) >= 0.0 && sp->GetTuple1(c) >= 0.0) {  // both ends elements (-1: a cluster)
      EXPECT_NE(rp->GetTuple1(c), sp->GetTuple1(c));  // a patch is flat: it never sees itself
    }
    partial += vis->GetTuple1(c) > 0.0 && vis->GetTuple1(c) < 1.0 ? 1 : 0;
    hidden += vis->GetTuple1(c) == 0.0 ? 1 : 0;
  }
  EXPECT_GT(partial, 0);  // the box shadows the floor: some links are partly visible, some hidden
  EXPECT_GT(hidden, 0);
}

struct BadRun {
  const char* args;
  const char* must_contain;
};

class CliErrors : public ::testing::TestWithParam<BadRun> {};

TEST_P(CliErrors, OneLineErrorNonZeroExitNoOutput) {
  const test::TempDir tmp;
  const fs::path out = tmp / "bad";
  std::string args = GetParam().args;
  for (size_t k; (k = args.find("DATA")) != std::string::npos;) args.replace(k, 4, kData);
  const Result r = run_cli(args + " -o " + out.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find(GetParam().must_contain), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "output written for bad input";
}

INSTANTIATE_TEST_SUITE_P(
    BadInputs, CliErrors,
    ::testing::Values(BadRun{"run DATA/bad/nan_coordinate.obj", "nan_coordinate.obj:6"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method pixmap --rays 4", "--rays"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method pixmap --max-edge 50", "--max-edge"},
                      BadRun{"run DATA/bad/reflectance_one.obj", "reflectance_one.mtl:3"},
                      BadRun{"run DATA/bad/negative_emission.obj", "negative_emission.mtl:4"},
                      BadRun{"run DATA/bad/degenerate_face.obj", "degenerate_face.obj:9"},
                      BadRun{"run DATA/bad/missing_material.obj", "no_such_material"},
                      BadRun{"run DATA/bad/missing_mtl_file.obj", "does_not_exist.mtl"},
                      BadRun{"run DATA/bad/parse_error.obj", "parse_error.obj:7"},
                      BadRun{"run DATA/bad/bad_index.obj", "bad_index.obj:8"},
                      BadRun{"run DATA/no_such_scene.obj", "no_such_scene.obj"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --bogus-flag", "bogus"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --min-angle 45", "min-angle"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --tolerance 0", "tolerance"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method matrix --max-memory 0.000001", "GiB"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method fastest", "--method"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method hierarchical --epsilon 0", "--epsilon"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --discontinuity some", "--discontinuity"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method matrix --export-links", "--export-links"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --min-area 1e-20", "--min-area"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --epsilon nan", "--epsilon: nan is not finite"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method matrix --epsilon 0.01", "--epsilon"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --max-memory 0.000001", "GiB allowed"},
                      BadRun{"mesh DATA/cornell_box/cornell_box.obj --max-shadow-lines -1", "--max-shadow-lines"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --max-edge 0.0001", "--max-edge 0.0001"},
                      BadRun{"mesh DATA/cornell_box/cornell_box.obj --max-edge 0.01", "use --max-edge"},
                      BadRun{"run DATA/cornell_box/cornell_box.obj --max-edge 1e-300", "at least 10^606 elements"},
                      // 545 k texels: 0.42 GB at the peak (0.62 GB before radiosity.vtu was
                      // written from views), where only their grids were counted (0.05 GB)
                      BadRun{"run DATA/cornell_box/cornell_box.obj --method pixmap --texel-size 2 --max-memory 0.25",
                             "0.25 GiB"}),
    [](const auto& info) {
      std::string name = std::to_string(info.index) + "_";
      for (char ch : std::string(info.param.must_contain))
        name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
      return name;
    });

TEST(Cli, QualityWritesOneRowPerPatchAndATotal) {
  const test::TempDir tmp;
  const fs::path out = tmp / "quality";
  const Result r = run_cli("quality " + kData + "/box_on_floor/box_on_floor.obj -o " + out.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream csv(out / "quality.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "patch_id,name,triangles,min_angle,max_angle,aspect_p50,aspect_p95,aspect_max,contact_segments,d1_segments,d2_segments,zero_area");
  int rows = 0, sum = 0, total = -1, floor_contacts = -1;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 12u) << line;
    if (f[0] == "-1") {
      total = std::stoi(f[2]);
    } else {
      ++rows;
      sum += std::stoi(f[2]);
      if (f[1] == "floor") floor_contacts = std::stoi(f[8]);
      EXPECT_GE(std::stod(f[3]), 20.0 - 1e-6) << line;  // the requested minimum angle
    }
  }
  EXPECT_EQ(rows, 7);  // box_on_floor has 7 patches
  EXPECT_EQ(total, sum);
  EXPECT_EQ(floor_contacts, 4);  // the box's footprint
}

namespace {
// The total row of a quality.csv as its fields.
std::vector<std::string> quality_total(const fs::path& csv_path) {
  std::ifstream csv(csv_path);
  std::string line;
  while (std::getline(csv, line))
    if (line.rfind("-1,", 0) == 0) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      return f;
    }
  return {};
}
}  // namespace

TEST(Cli, QualityOfAWrittenMeshMatchesTheSceneRunWithShadowLines) {
  const test::TempDir tmp;
  const fs::path a = tmp / "quality_full", m = tmp / "mesh_full", b = tmp / "quality_vtu";
  const std::string scene = kData + "/box_on_floor/box_on_floor.obj --discontinuity full --max-edge 0.5 -q";
  ASSERT_EQ(run_cli("quality " + scene + " -o " + a.string()).status, 0);
  ASSERT_EQ(run_cli("mesh " + scene + " -o " + m.string()).status, 0);
  const Result r = run_cli("quality " + (m / "mesh.vtu").string() + " -o " + b.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto from_scene = quality_total(a / "quality.csv"), from_mesh = quality_total(b / "quality.csv");
  ASSERT_EQ(from_scene.size(), 12u);
  ASSERT_EQ(from_mesh.size(), 12u);
  EXPECT_EQ(from_mesh[2], from_scene[2]);    // triangles
  EXPECT_EQ(from_mesh[8], "4");              // D0: the box's footprint
  EXPECT_EQ(from_mesh[9], from_scene[9]);    // D1 segments (read back from discontinuities.vtu)
  EXPECT_GT(std::stoi(from_mesh[9]), 0);
  EXPECT_EQ(from_mesh[10], "0");             // the box is axis-aligned with the light: no D2
  // A file that is not a mesh is refused with its name.
  const Result bad = run_cli("quality " + (m / "summary.json").string() + " -o " + b.string() + " -q");
  EXPECT_NE(bad.status, 0);
  const Result bad_vtu = run_cli("quality " + (m / "discontinuities.vtu").string() + " -o " + b.string() + " -q");
  EXPECT_NE(bad_vtu.status, 0);
  EXPECT_NE(bad_vtu.err.find("discontinuities.vtu"), std::string::npos) << bad_vtu.err;
}

TEST(Cli, ASecondRunIntoTheSameDirectoryLeavesOnlyItsOwnFiles) {
  const test::TempDir tmp;
  // The first run writes links.vtu and three refinement rounds; the second
  // (matrix) writes neither: nothing of the first may be left beside it.
  const fs::path out = tmp / "rerun";
  const std::string scene = kData + "/box_on_floor/box_on_floor.obj";
  ASSERT_EQ(run_cli("run " + scene + " --no-png -q --export-links --epsilon 0.01 -o " + out.string()).status, 0);
  ASSERT_TRUE(fs::exists(out / "links.vtu"));
  ASSERT_TRUE(fs::exists(out / "radiosity_round_1.vtu"));
  {
    std::ofstream mine(out / "notes.txt");  // not ours: kept
    mine << "user file\n";
  }
  ASSERT_EQ(run_cli("run " + scene + " --no-png -q --method matrix -o " + out.string()).status, 0);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(out)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"discontinuities.vtu", "notes.txt", "radiosity.vtu", "summary.json"}));
}

// Guards the endless mesher loop of issue 10: one `v` line of the Cornell box
// written twice shifts every later index, and the ceiling's quads became bow
// ties that `mesh --max-edge 300` refined without end. Now refused at once.
TEST(Cli, ADuplicatedVertexLineIsAnErrorNotAnEndlessMesh) {
  const test::TempDir tmp;
  const fs::path dir = tmp / "dup_v";
  const std::string scene = test::write_edited_obj(kData + "/cornell_box/cornell_box", dir,
                                                   [](const std::string& line, int n) {
                                                     return n == 7 ? line + '\n' + line : line;  // `sed 7p`
                                                   });
  const Result r = run_cli("mesh " + scene + " --max-edge 300 -q -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("not a simple polygon"), std::string::npos) << r.err;
}

TEST(Cli, NamesThatAreNotUtf8AreWrittenReplacedNotAnInternalError) {
  const test::TempDir tmp;
  const fs::path dir = tmp / "latin1";
  const std::string scene = test::write_edited_obj(
      kData + "/parallel_plates/parallel_plates", dir, [](const std::string& line, int) {
        return line.rfind("o receiver", 0) == 0 ? std::string("o r\xE9\x63\x65pteur") : line;  // Latin-1 e-acute
      });
  const Result r = run_cli("run " + scene + " --no-png -q -o " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(dir / "out");
  int replaced = 0;
  for (const auto& p : s["patches"])
    if (p["name"].get<std::string>() == "r\xEF\xBF\xBD" "cepteur") ++replaced;  // U+FFFD in UTF-8
  EXPECT_EQ(replaced, 1);
}

TEST(Cli, ExitCodesAreZeroOneAndTwo) {
  const test::TempDir tmp;
  // 0 success (and --help), 1 bad input, 2 usage (a flag or argument the
  // program does not know or cannot parse).
  EXPECT_EQ(run_cli("--help").status, 0);
  EXPECT_EQ(run_cli("run --help").status, 0);
  EXPECT_EQ(run_cli("run").status, 2);
  EXPECT_EQ(run_cli("run " + kData + "/cornell_box/cornell_box.obj --bogus-flag").status, 2);
  EXPECT_EQ(run_cli("run " + kData + "/cornell_box/cornell_box.obj --rays many").status, 2);
  EXPECT_EQ(run_cli("run " + kData + "/cornell_box/cornell_box.obj --rays 0x10").status, 2);  // the files' number syntax
  EXPECT_EQ(run_cli("frobnicate").status, 2);
  const fs::path out = tmp / "exit1";
  EXPECT_EQ(run_cli("run " + kData + "/bad/nan_coordinate.obj -o " + out.string()).status, 1);
  // An output directory that cannot be made is bad input, found before any work.
  const fs::path file = out.string() + "_file";
  std::ofstream(file) << "x";
  const Result r = run_cli("run " + kData + "/parallel_plates/parallel_plates.obj -o " + (file / "sub").string());
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(test::mentions(r.err, {(file / "sub").string(), "not a directory"}));
}

TEST(Cli, MeshReadsTheJsonBunnySceneWithItsMaterials) {
  const test::TempDir tmp;
  const fs::path out = tmp / "bunny_mesh";
  const std::string scene = kData + "/bunny/bunny_room.json";
  const Result r = run_cli("mesh " + scene + " --max-edge 10 --discontinuity contacts -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = read_summary(out);
  // room.obj: floor, 4 walls, 4 ceiling pieces and the light; bunny.ply: 3674 triangles, 1839 vertices.
  EXPECT_EQ(s["counts"]["faces_read"], 3684);
  EXPECT_EQ(s["counts"]["patches"], 3684);
  EXPECT_EQ(s["counts"]["materials"], 5);
  EXPECT_EQ(s["counts"]["vertices_welded"], 3674 * 3 + 10 * 4 - (1839 + 16));
  EXPECT_GE(s["counts"]["elements"].get<int>(), 3684);
  // Per patch: the JSON's material for the bunny, the MTL's for the room; the
  // bunny's area (0.48 m tall) as test_readers' Bunny tests compute it.
  ASSERT_EQ(s["patches"].size(), 3684u);
  double bunny_area = 0.0;
  for (const auto& patch : s["patches"])
    if (patch["name"] == "bunny") {
      EXPECT_EQ(patch["material"], "clay");
      bunny_area += patch["area"].get<double>();
    }
  EXPECT_EQ(s["patches"][0]["name"], "floor");
  EXPECT_EQ(s["patches"][0]["material"], "white");
  EXPECT_NEAR(bunny_area, 0.5467231782172347, 1e-12);
}

TEST(Cli, APlyFileAloneIsRefusedWithTheWayToGiveItAMaterial) {
  const test::TempDir tmp;
  const fs::path out = tmp / "bunny_ply";
  const Result r = run_cli("run " + kData + "/bunny/bunny.ply -o " + out.string());
  EXPECT_NE(r.status, 0);
  EXPECT_TRUE(test::mentions(r.err, {"bunny.ply: ", "no materials"}));
  EXPECT_NE(r.err.find("{\"file\": \"bunny.ply\", \"material\": \"grey\"}"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

namespace {

// Lines of `path` that start with `prefix`.
int count_lines(const fs::path& path, const std::string& prefix) {
  std::ifstream in(path);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

}  // namespace

using radmesh::PixmapState;
using radmesh::read_pixmap_state;

TEST(Cli, PixmapRunSavesItsStateAndLightmapsAndAResumeIsBitIdentical) {
  const test::TempDir tmp;
  const std::string scene = kData + "/box_on_floor/box_on_floor.obj";
  const fs::path a = tmp / "pixmap_a", b = tmp / "pixmap_b", c = tmp / "pixmap_c";
  const std::string opts = " --method pixmap --hemicube-res 64 --unshot 0 --no-png";
  Result r = run_cli("run " + scene + opts + " --shots 20 --snapshot-every 10 -o " + a.string());
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* f : {"radiosity.vtu", "summary.json", "pixmaps/state.json", "pixmaps/pixmap_0.vti",
                        "lightmaps/pixmap_0.png", "lightmapped.obj", "lightmapped.mtl", "radiosity.pvd",
                        "radiosity_round_0.vtu", "radiosity_round_1.vtu"})
    EXPECT_TRUE(fs::exists(a / f)) << f;
  const nlohmann::json s = read_summary(a);
  EXPECT_EQ(s["solver"]["shots"], 20);
  EXPECT_EQ(s["field"]["mode"], "texels");
  EXPECT_FALSE(fs::exists(a / "radiosity_round_2.vtu"));  // a snapshot every 10 of 20 shots
  // One vt per v; every pixmap has its texture.
  EXPECT_EQ(count_lines(a / "lightmapped.obj", "v "), count_lines(a / "lightmapped.obj", "vt "));
  EXPECT_EQ(count_lines(a / "lightmapped.mtl", "map_Kd lightmaps/pixmap_"), s["solver"]["pixmaps"].get<int>());
  // 20 shots, resumed to 45, against 45 in one run.
  r = run_cli("run " + scene + opts + " --shots 45 --resume " + a.string() + " -o " + b.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(read_summary(b)["solver"]["shots_this_run"], 25);
  r = run_cli("run " + scene + opts + " --shots 45 -o " + c.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const PixmapState resumed = read_pixmap_state(b.string()), direct = read_pixmap_state(c.string());
  EXPECT_EQ(resumed.shots, 45);
  EXPECT_EQ(resumed.radiosity, direct.radiosity);
  EXPECT_EQ(resumed.unshot, direct.unshot);
  EXPECT_EQ(resumed.power_absorbed, direct.power_absorbed);
  // Other options, another method: refused, naming what differs.
  r = run_cli("run " + scene + " --method pixmap --hemicube-res 128 --resume " + a.string() + " -o " + b.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(test::mentions(r.err, {"cannot resume", "--hemicube-res 64", "--hemicube-res 128"}));
  r = run_cli("run " + scene + " --method matrix --resume " + a.string() + " -o " + b.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(test::mentions(r.err, {"--resume", "--method pixmap"}));
  r = run_cli("run " + scene + " --method pixmap --resume " + c.string() + "/lightmaps -o " + b.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("pixmaps/state.json: cannot open"), std::string::npos) << r.err;
}

TEST(Cli, CtrlCStopsAPixmapRunWhichSavesItsStateAndSaysHowToResume) {
  const test::TempDir tmp;
  const fs::path out = tmp / "pixmap_interrupt";
  const fs::path err = out.string() + "_err.txt";
  // No stopping rule: only the interrupt ends it.
  const std::string cmd = "DISPLAY= timeout --foreground --preserve-status -s INT 3 " + kExe + " run " + kData +
                          "/cornell_box/cornell_box.obj --method pixmap --unshot 0 --no-png -o " + out.string() +
                          " >/dev/null 2>" + err.string();
  const int rc = std::system(cmd.c_str());
  std::ifstream in(err);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(WEXITSTATUS(rc), 130) << text;
  EXPECT_NE(text.find("interrupted after"), std::string::npos) << text;
  EXPECT_NE(text.find("--resume " + out.string()), std::string::npos) << text;
  const PixmapState st = read_pixmap_state(out.string());
  EXPECT_GT(st.shots, 0);
  EXPECT_EQ(read_summary(out)["solver"]["interrupted"], 1);
}

// ---------------------------------------------------------------- full disks

namespace {

using radmesh::test::folder;
using radmesh::test::names;

// A flat grid of n x n squares, two triangles each (one patch each), all
// named `name`, in DIR/grid.obj.
std::string write_grid(const fs::path& dir, int n, const std::string& name) {
  fs::create_directories(dir);
  std::ofstream(dir / "grid.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
  std::ofstream obj(dir / "grid.obj");
  obj << "mtllib grid.mtl\n";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) obj << "v " << i << " 0 " << j << "\n";
  obj << "o " << name << "\nusemtl grey\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
      obj << "f " << a << ' ' << d << ' ' << c << "\nf " << a << ' ' << c << ' ' << b << "\n";
    }
  return (dir / "grid.obj").string();
}

// A run whose largest file is `largest`: its arguments (DATA: the test data,
// SCENE: the scene `scene` writes into a folder and returns, when given).
struct FullDiskRun {
  const char* largest;
  const char* args;
  std::function<std::string(const fs::path&)> scene;
};

std::ostream& operator<<(std::ostream& os, const FullDiskRun& r) { return os << r.largest; }

class CliFullDisk : public ::testing::TestWithParam<FullDiskRun> {};

}  // namespace

// A run with a limit halfway between the size of its largest file and the
// next largest: that file cannot be written whole, every other one can
// (the files written before it are complete). The run exits 1 (not killed, by SIGXFSZ or a crash in
// a writer) with one line naming that file, and leaves the output folder
// as it was: an earlier run's files of the same names unchanged, a stale
// round file this run would have removed still there, a user's file kept,
// and no file (or temporary file) of its own.
TEST_P(CliFullDisk, TheLargestFileFailsAndTheFolderIsLeftAsItWas) {
  const test::TempDir tmp;
  std::string args = GetParam().args;
  for (size_t k; (k = args.find("DATA")) != std::string::npos;) args.replace(k, 4, kData);
  if (GetParam().scene) {
    const std::string scene = GetParam().scene(tmp / "scene");
    for (size_t k; (k = args.find("SCENE")) != std::string::npos;) args.replace(k, 5, scene);
  }
  const fs::path whole = tmp / "whole", out = tmp / "out", fresh = tmp / "new" / "out";
  const Result r = run_cli(args + " -o " + whole.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto files = folder(whole);
  std::string largest;
  size_t size = 0, second = 0;
  for (const auto& [name, content] : files) {
    if (content.size() > size) {
      second = size;
      size = content.size();
      largest = name;
    } else {
      second = std::max(second, content.size());
    }
  }
  ASSERT_EQ(largest, GetParam().largest) << names(files);
  ASSERT_GT(size, second + 1000);
  const long limit = static_cast<long>((size + second) / 2);
  // An earlier run's results in the folder.
  for (const auto& [name, content] : files) {
    fs::create_directories((out / name).parent_path());
    std::ofstream(out / name) << "an earlier run's " << name << "\n";
  }
  std::ofstream(out / "radiosity_round_7.vtu") << "an earlier run's round 7\n";
  std::ofstream(out / "notes.txt") << "the user's notes\n";
  const auto before = folder(out);

  const Result full = run_cli(args + " -o " + out.string(), limit);
  EXPECT_EQ(full.status, 1) << full.err;
  EXPECT_EQ(std::count(full.err.begin(), full.err.end(), '\n'), 1) << full.err;
  EXPECT_TRUE(test::mentions(full.err, {"radmesh: error: ", (out / largest).string()}));
  const auto after = folder(out);
  EXPECT_TRUE(after == before) << "before: " << names(before) << "\nafter: " << names(after);

  // Into a folder the run makes: none left.
  const Result into_new = run_cli(args + " -o " + fresh.string(), limit);
  EXPECT_EQ(into_new.status, 1) << into_new.err;
  EXPECT_TRUE(test::mentions(into_new.err, {(fresh / largest).string()}));
  EXPECT_FALSE(fs::exists(fresh.parent_path())) << names(folder(fresh.parent_path()));
}

INSTANTIATE_TEST_SUITE_P(
    Files, CliFullDisk,
    ::testing::Values(
        FullDiskRun{"radiosity.vtu", "run DATA/parallel_plates/parallel_plates.obj --method matrix --no-png -q", {}},
        // After the .vtu, the round files, the .pvd and the contact lines.
        FullDiskRun{"links.vtu", "run DATA/box_on_floor/box_on_floor.obj --method hierarchical --epsilon 0.01 "
                                 "--export-links --no-png -q", {}},
        // After the .vtu, the pixmap state, the lightmaps and the MTL.
        FullDiskRun{"lightmapped.obj", "run DATA/parallel_plates/parallel_plates.obj --method pixmap --no-png -q", {}},
        // After the .vtu: 2000 probes.
        FullDiskRun{"probes.csv", "run DATA/parallel_plates/parallel_plates.obj --method matrix --no-png -q --probe SCENE",
                    [](const fs::path& dir) {
                      fs::create_directories(dir);
                      std::ofstream p(dir / "probes.txt");
                      for (int k = 0; k < 2000; ++k)
                        p << "p" << k << ' ' << 0.05 + 0.9 * (k % 40) / 40 << ' ' << 0.05 + 0.9 * (k / 40) / 50
                          << " 1 0 0 -1\n";
                      return (dir / "probes.txt").string();
                    }},
        // After the .vtu: 800 patches with a long name each in the summary.
        FullDiskRun{"summary.json", "mesh SCENE --max-edge 1000 --discontinuity off -q",
                    [](const fs::path& dir) { return write_grid(dir, 20, std::string(1000, 'g')); }},
        // After the .vtu and summary.json: 10082 patches, beyond the summary's list.
        FullDiskRun{"patches.csv", "mesh SCENE --max-edge 1000 --discontinuity off -q",
                    [](const fs::path& dir) { return write_grid(dir, 71, std::string(300, 'g')); }}),
    [](const ::testing::TestParamInfo<FullDiskRun>& info) {
      std::string name = std::to_string(info.index) + "_" + info.param.largest;
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

// The pixmap run's radiosity.vtu (its display mesh), the first file a run
// writes, limited to half its size: where VTK's XML writer crashed (SIGSEGV,
// SIGBUS or an abort in free) and left radiosity.vtu.tmp. Exit 1 naming it,
// and nothing left, not even the folder the run made.
TEST(Cli, AFileSizeLimitInThePixmapVtuFailsTheRunWithoutACrash) {
  const test::TempDir tmp;
  const std::string args = "run " + kData + "/parallel_plates/parallel_plates.obj --method pixmap --no-png -q";
  const fs::path whole = tmp / "whole", out = tmp / "new" / "out";
  const Result r = run_cli(args + " -o " + whole.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const long half = static_cast<long>(fs::file_size(whole / "radiosity.vtu") / 2);
  for (const long limit : {half, half / 8}) {
    const Result full = run_cli(args + " -o " + out.string(), limit);
    EXPECT_EQ(full.status, 1) << "limit " << limit << ": " << full.err;
    EXPECT_TRUE(test::mentions(full.err, {"radmesh: error: ", (out / "radiosity.vtu").string()}));
    EXPECT_FALSE(fs::exists(out.parent_path())) << names(folder(out.parent_path()));
  }
}

// A real full disk: a tmpfs of `bytes`, mounted in a mount namespace of the
// test's own (unshare; the test is skipped where that is not allowed).
// Runs `args` into it: exit 1 with a message naming `file` of its output
// folder, and nothing left on the disk (ls -A).
void expect_full_disk_fails_at(const test::TempDir& tmp, const std::string& args, long bytes, const std::string& file) {
  const fs::path mnt = tmp / "mnt", status = tmp / "status.txt", listing = tmp / "listing.txt", err = tmp / "err.txt";
  fs::create_directories(mnt);
  const std::string inside = "mount -t tmpfs -o size=" + std::to_string(bytes / 1024) + "k tmpfs " + mnt.string() +
                             " || exit 99; DISPLAY= " + kExe + " " + args + " -o " + mnt.string() + "/out 2>" +
                             err.string() + " >/dev/null; echo $? >" + status.string() + "; ls -A " + mnt.string() +
                             " >" + listing.string();
  bool mounted = false;
  for (const char* unshare : {"unshare -rm", "unshare -m"}) {
    const std::string cmd = std::string(unshare) + " sh -c '" + inside + "' 2>/dev/null";
    const int rc = std::system(cmd.c_str());
    if (WIFEXITED(rc) && WEXITSTATUS(rc) == 0) {
      mounted = true;
      break;
    }
  }
  if (!mounted) GTEST_SKIP() << "cannot mount a small tmpfs here (unshare -rm and unshare -m both refused)";
  std::ifstream s(status), l(listing), e(err);
  int code = -1;
  s >> code;
  const std::string left((std::istreambuf_iterator<char>(l)), std::istreambuf_iterator<char>()),
      said((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_EQ(code, 1) << said;
  EXPECT_TRUE(test::mentions(said, {"radmesh: error: ", (mnt / "out" / file).string()}));
  EXPECT_EQ(left, "") << "left on the full disk: " << left;
}

// Whole pages of a file of `size` bytes (what it takes of a tmpfs).
long pages(size_t size) {
  const long page = ::sysconf(_SC_PAGESIZE);
  return (static_cast<long>(size) + page - 1) / page;
}

// The disk fills while the pixmap run's radiosity.vtu (its display mesh:
// where VTK's XML writer crashed) is written, the first file of the run:
// exit 1 naming it, nothing left.
TEST(Cli, ADiskThatFillsInTheVtuFailsTheRunWhichLeavesNothingOfItsOwn) {
  const test::TempDir tmp;
  const std::string args = "run " + kData + "/parallel_plates/parallel_plates.obj --method pixmap --no-png -q";
  const Result r = run_cli(args + " -o " + (tmp / "whole").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const long half = pages(fs::file_size(tmp / "whole" / "radiosity.vtu")) / 2;
  expect_full_disk_fails_at(tmp, args, half * ::sysconf(_SC_PAGESIZE), "radiosity.vtu");
}

// The disk fills while summary.json is written, after the .vtu, the round
// files and the .pvd of a hierarchical run: exit 1 naming summary.json, and
// nothing left: not the complete radiosity.vtu, not the folder it made.
TEST(Cli, ADiskThatFillsAtTheSummaryFailsTheRunWhichLeavesNothingOfItsOwn) {
  const test::TempDir tmp;
  const std::string args = "run " + kData + "/parallel_plates/parallel_plates.obj --method hierarchical --no-png -q";
  const Result r = run_cli(args + " -o " + (tmp / "whole").string());
  ASSERT_EQ(r.status, 0) << r.err;
  long n = 0;
  for (const auto& [name, content] : folder(tmp / "whole"))
    n += name == "summary.json" ? pages(content.size()) - 1 : pages(content.size());
  ASSERT_GE(pages(fs::file_size(tmp / "whole" / "summary.json")), 2);
  expect_full_disk_fails_at(tmp, args, n * ::sysconf(_SC_PAGESIZE), "summary.json");
}
