// The public API's one-call form (radmesh::solve with typed options) and the
// option tables behind every entry point: the typed path and the text path
// give the same result, ranges hold on both, a shared option a method does
// not use is refused, and a result outlives its scene.

#include "radmesh/radmesh.h"

#include <gtest/gtest.h>

#include "test_util.h"

#include <filesystem>
#include <memory>
#include <new>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace radmesh;
using radmesh::test::kData;

namespace {

Scene box_on_floor() { return read_obj_scene(kData + "/box_on_floor/box_on_floor.obj"); }

}  // namespace

TEST(Solve, TypedOptionsGiveWhatTheirTextGives) {
  const Scene scene = box_on_floor();
  HierarchicalOptions typed;
  typed.epsilon = 0.02;
  typed.tvertex = TVertexMode::anchor;
  const Result a = solve(scene, typed);
  const Result b = solve(scene, "hierarchical", {{"epsilon", "0.02"}, {"tvertex", "anchor"}});
  ASSERT_EQ(a.mesh.triangles, b.mesh.triangles);
  ASSERT_EQ(a.solution.element.size(), b.solution.element.size());
  for (size_t t = 0; t < a.solution.element.size(); ++t) EXPECT_EQ(a.solution.element[t], b.solution.element[t]);
  EXPECT_EQ(a.method, "hierarchical");
  // The options as solved with, every one of the method's, numbers as numbers.
  ASSERT_EQ(a.options.size(), find_method("hierarchical").options.size());
  for (const OptionValue& v : a.options) {
    if (v.name == "epsilon") {
      EXPECT_EQ(v.number, 0.02);
    }
    if (v.name == "tvertex") {
      EXPECT_EQ(v.text, "anchor");
    }
  }
  // Patch means of the field shown: the same as the summary's function.
  const std::vector<Rgb> means = a.patch_means();
  const std::vector<Rgb> direct = patch_mean_radiosity(scene, a.mesh, a.solution.nodal);
  ASSERT_EQ(means.size(), scene.patches.size());
  for (size_t p = 0; p < means.size(); ++p) EXPECT_EQ(means[p], direct[p]);
}

TEST(Solve, AnOptionOutOfRangeIsAnInputErrorNamingIt) {
  const Scene scene = box_on_floor();
  HierarchicalOptions ho;
  ho.epsilon = 2.0;  // [1e-9, 1]
  const test::Thrown t = test::thrown<InputError>([&] { solve(scene, ho); });
  EXPECT_TRUE(t.names("epsilon"));
  EXPECT_TRUE(test::contains(t.message, "epsilon 2")) << t.message;
  // The same range on the text path and in the solver itself.
  EXPECT_TRUE(test::thrown<InputError>([&] { solve(scene, "hierarchical", {{"epsilon", "2"}}); }).names("epsilon"));
  const Mesh mesh = mesh_scene(scene, MeshingOptions{});
  EXPECT_TRUE(test::thrown<InputError>([&] { HierarchicalSolver solver(scene, mesh, {}, ho); }).names("epsilon"));
  SolveOptions so;
  so.rays = 0;  // [1, 4096]
  EXPECT_TRUE(test::thrown<InputError>([&] { solve(scene, MatrixOptions{}, so); }).names("rays"));
  MeshingOptions mo;
  mo.min_angle = 45.0;  // [0, 30]
  EXPECT_TRUE(test::thrown<InputError>([&] { resolve_meshing_options(scene, mo); }).names("min_angle"));
}

TEST(Solve, ASharedOptionTheMethodDoesNotUseIsRefused) {
  // The pixmap method's hemicubes see occlusion: shadow rays are not its,
  // unless the field is gathered (the gather casts them).
  const Scene scene = box_on_floor();
  PixmapOptions po;
  po.hemicube_res = 16;
  po.shots = 3;
  SolveOptions so;
  so.rays = 4;
  const test::Thrown t = test::thrown<InputError>([&] { solve(scene, po, so); });
  EXPECT_TRUE(t.names("rays"));
  EXPECT_TRUE(test::contains(t.message, "pixmap")) << t.message;
  so.field = FieldMode::gather;
  EXPECT_NO_THROW(solve(scene, po, so));
  // The same check for the program's flags, by name.
  EXPECT_TRUE(test::thrown<InputError>([&] {
                check_shared_options(find_method("pixmap"), {"max_edge"}, FieldMode::automatic);
              }).names("max_edge"));
  EXPECT_NO_THROW(check_shared_options(find_method("matrix"), {"max_edge", "rays"}, FieldMode::automatic));
}

TEST(Solve, AResultOutlivesItsSceneAndWritesItsFiles) {
  // The pixmap result's files (its state and lightmaps) are written from
  // what the result holds, after the scene it was made from is gone.
  std::unique_ptr<Result> r;
  {
    const Scene scene = box_on_floor();
    PixmapOptions po;
    po.hemicube_res = 16;
    po.shots = 3;
    r = std::make_unique<Result>(solve(scene, po));
  }
  const test::TempDir dir;
  write_vtu((dir / "radiosity.vtu").string(), *r);
  write_summary((dir / "summary.json").string(), *r);
  ASSERT_TRUE(r->files.write);
  const std::vector<std::string> written = r->files.write(dir.string(), r->mesh);
  EXPECT_FALSE(written.empty());
  for (const std::string& f : written) EXPECT_TRUE(std::filesystem::exists(f)) << f;
  EXPECT_TRUE(std::filesystem::exists(dir / "radiosity.vtu"));
  EXPECT_TRUE(std::filesystem::exists(dir / "summary.json"));
  // Its saved state reads back through the method's own hook and resumes.
  const std::shared_ptr<const MethodState> state = read_method_state(find_method("pixmap"), dir.string());
  ASSERT_TRUE(state);
  EXPECT_TRUE(test::thrown<InputError>([&] { read_method_state(find_method("matrix"), dir.string()); })
                  .names("resume"));
}

TEST(Solve, AnAllocationTheSystemRefusesIsANumericalErrorNotAnInternalOne) {
  // A method whose solve runs out of memory: run_method says so as a
  // radmesh error naming max_memory, not std::bad_alloc.
  Method m = find_method("matrix");
  m.solve = [](const Scene&, const Mesh&, const SolveOptions&, const MethodOptions&, const SolveCallbacks&) -> MethodResult {
    throw std::bad_alloc();
  };
  const Scene scene = box_on_floor();
  const Mesh mesh = mesh_scene(scene, MeshingOptions{});
  const test::Thrown t = test::thrown<NumericalError>([&] { run_method(m, scene, mesh, {}, OptionValues{}); });
  EXPECT_TRUE(t.names("max_memory"));
  EXPECT_TRUE(t.says({"box_on_floor.obj", "out of memory"}));
}

TEST(Solve, TheMemoryLimitIsWithinTheProcesssDataLimit) {
  // Under ulimit -d (or -v) an allocation past the limit fails whatever the
  // machine holds: the default limit is half of it. In a child process, so
  // that the limit does not outlive the check.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    rlimit r{};
    getrlimit(RLIMIT_DATA, &r);
    r.rlim_cur = rlim_t{4} << 30;
    if (r.rlim_max != RLIM_INFINITY && r.rlim_max < r.rlim_cur) r.rlim_cur = r.rlim_max;
    if (setrlimit(RLIMIT_DATA, &r) != 0) _exit(2);
    const double limit = memory_limit_bytes(SolveOptions{});
    _exit(limit <= 0.5 * static_cast<double>(r.rlim_cur) ? 0 : 1);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(OptionTable, ReadsChecksAndListsAStruct) {
  struct Opts {
    double size = 0.5;
    int count = 3;
    bool flag = false;
    FieldMode mode = FieldMode::fit;
  };
  OptionTable<Opts> table("test");
  table.real("size", &Opts::size, "m", "a size", 0.0, 1.0)
      .integer("count", &Opts::count, "", "a count", 1, 10)
      .flag("flag", &Opts::flag, "a flag")
      .choice("mode", &Opts::mode, "a mode", {{"gather", FieldMode::gather}, {"fit", FieldMode::fit}});
  // Defaults from the struct; a choice's default first.
  EXPECT_EQ(table.specs()[0].default_value, 0.5);
  EXPECT_EQ(table.specs()[3].choices, (std::vector<std::string>{"fit", "gather"}));
  const Opts o = table.parse({{"size", "0.25"}, {"count", "7"}, {"flag", "true"}, {"mode", "gather"}});
  EXPECT_EQ(o.size, 0.25);
  EXPECT_EQ(o.count, 7);
  EXPECT_TRUE(o.flag);
  EXPECT_EQ(o.mode, FieldMode::gather);
  EXPECT_EQ(table.changed(o), (std::vector<std::string>{"size", "count", "flag", "mode"}));
  EXPECT_TRUE(table.changed(Opts{}).empty());
  const std::vector<OptionValue> v = table.values(o);
  EXPECT_EQ(v[3].text, "gather");
  EXPECT_EQ(v[2].text, "true");
  // Out of range, not an integer, not a number, not a choice, not an option.
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"size", "1.5"}}); }).names("size"));
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"count", "2.5"}}); }).names("count"));
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"count", "many"}}); }).names("count"));
  // One number syntax, the scene files' (0x2 is 2 to strtod).
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"count", "0x2"}}); }).says({"count 0x2", "hexadecimal"}));
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"size", "nan"}}); }).says({"size nan", "not finite"}));
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"mode", "mean"}}); }).names("mode"));
  EXPECT_TRUE(test::thrown<InputError>([&] { table.parse({{"colour", "red"}}); }).names("colour"));
  Opts bad;
  bad.count = 11;
  EXPECT_TRUE(test::thrown<InputError>([&] { table.check(bad); }).names("count"));
}
