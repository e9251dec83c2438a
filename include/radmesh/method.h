// The solver contract: every radiosity method is one entry of one table,
// with its declared options, its recommended initial meshing and a solve
// that returns a result on its own mesh with named counters. The CLI, the
// summary, the benchmark and the conformance tests loop over this table.
//
// Adding a method: write its solver in its own files (a one-off
// solve_x(...) and, where state lives between calls, a solver class) and an
// x_method.cpp whose `Method make_x_method()` declares its options and
// adapts its result (matrix_method.cpp, hierarchical_method.cpp), then add
// its line to `methods()` in methods.cpp.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/progress.h"
#include "radmesh/scene.h"
#include "radmesh/field.h"
#include "radmesh/pixmap.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace radmesh {

// One option a method takes. The name is the same everywhere: the CLI flag
// is "--" + name with '_' written '-', the summary key is the name.
struct OptionSpec {
  enum class Kind { real, integer, choice, flag };
  std::string name;
  Kind kind = Kind::real;
  std::string unit;   // "" when dimensionless
  std::string help;   // one sentence, without the default
  double default_value = 0.0;  // real, integer, flag (0 or 1)
  double min = 0.0, max = 0.0;  // inclusive range (real, integer)
  std::vector<std::string> choices;  // choice: the accepted values, the default first

  std::string flag() const;  // "--min-area"
  std::string default_text() const;
};

// "--" + name with '_' written '-': the command-line flag of an option.
std::string option_flag(const std::string& name);

// Option values as given (name -> text, e.g. from the command line). A
// method's options not given take their defaults.
using OptionValues = std::map<std::string, std::string>;

// Values checked against a method's declarations: every declared option has
// a value (given or default). Throws InputError naming the flag and value.
class MethodOptions {
public:
  MethodOptions() = default;
  MethodOptions(const std::vector<OptionSpec>& specs, const OptionValues& given, const std::string& method);

  double number(const std::string& name) const;  // real, integer, flag (0/1)
  const std::string& text(const std::string& name) const;  // every kind, as given or its default
  const OptionSpec& spec(const std::string& name) const;   // InputError when not declared
  // (name, value) in declaration order, numbers as numbers, for summaries.
  const std::vector<std::pair<std::string, std::string>>& items() const { return items_; }

private:
  std::vector<OptionSpec> specs_;
  std::vector<std::pair<std::string, std::string>> items_;
  std::map<std::string, double> numbers_;
};

// A count or measure a method publishes: the summary writes it under its
// name, the benchmark and tests read it by name.
struct Counter {
  std::string name;
  std::vector<double> values;  // one value, or a series (per round, per channel)
  std::string unit;            // "" when a count
  bool series = false;
  bool integral = true;
};
Counter count(std::string name, double value, std::string unit = "");
Counter measure(std::string name, double value, std::string unit = "");
Counter count_series(std::string name, std::vector<double> values, std::string unit = "");

// Line segments with cell fields (e.g. a hierarchy's links), written as
// NAME.vtu by the CLI.
struct LineSet {
  std::vector<std::array<Vec3, 2>> segments;
  std::vector<std::pair<std::string, std::vector<int>>> int_fields;
  std::vector<std::pair<std::string, std::vector<double>>> real_fields;
};

// What a method returns: a solution on its own mesh (the initial mesh, or
// one it refined), extra per-triangle integer fields for the .vtu, extra
// line sets, counters and the wall time of its phases.
struct MethodResult {
  Mesh mesh;
  Solution solution;  // per triangle of `mesh` and per vertex; common counts in solution.stats
  std::vector<std::pair<std::string, std::vector<int>>> cell_fields;
  std::vector<std::pair<std::string, LineSet>> line_sets;  // (file stem, lines)
  std::vector<Counter> counters;
  std::vector<std::pair<std::string, double>> seconds;  // phase -> wall seconds, in order
  std::string report;  // one line for people ("24128 leaves, 493567 links, ...")
  FieldReport field;   // how solution.nodal was made (run_method)
  // The pixmap method's texel grids and state, for the files that save,
  // resume and display them (io/pixmap_io.h); null for other methods.
  std::shared_ptr<const PixmapOutput> pixmaps;
  bool interrupted = false;  // stopped early by SolveCallbacks::cancelled
  // What the result says is likely wrong with the scene (run_method): no
  // light reached any surface that reflects.
  std::vector<std::string> warnings;

  const Counter* counter(const std::string& name) const;  // nullptr when absent
};

struct SolveCallbacks {
  ProgressFn progress;
  // Called after every refinement round of a method that has rounds (or
  // every --snapshot-every shots of the pixmap method), with the result as
  // it then stands (for a series of files).
  std::function<void(const MethodResult&, int round)> on_round;
  // Polled by methods that can stop early and still return a consistent
  // result (Method::resumable): true stops them (MethodResult::interrupted).
  std::function<bool()> cancelled;
  // A saved state to continue from (Method::resumable methods only).
  std::shared_ptr<const PixmapState> resume;
};

struct Method {
  std::string name;
  std::string help;  // one sentence for --help
  std::vector<OptionSpec> options;
  // Option values for a quick run (the conformance tests, the benchmark's
  // --quick): coarser, the same physics.
  OptionValues quick;
  // The initial meshing this method works best from: the CLI and the bench
  // start from these and apply what the user gave on top.
  std::function<MeshingOptions(const Scene&)> meshing;
  std::function<MethodResult(const Scene&, const Mesh&, const SolveOptions&, const MethodOptions&,
                             const SolveCallbacks&)>
      solve;
  // It can stop on SolveCallbacks::cancelled and resume from a saved state.
  bool resumable = false;
  // What the conformance tests (tests/test_methods.cpp) may expect of it on
  // their closed forms. The defaults are exact form factors: errors vanish
  // with the solve's tolerance. A method whose form factors are estimates
  // that do not (the pixmap method: hemicubes shot from block centres,
  // float state) declares its relative errors here.
  struct Accuracy {
    double element = 0.0;     // of an element value
    double patch_mean = 0.0;  // of a patch's mean
    double residual = 0.0;    // the solve's final residual at its defaults
    bool casts_rays = true;   // occlusion by shadow rays (SolveStats::rays_cast)
    bool error_bound = true;  // reports a max-norm bound (SolveStats::error_bound)
  } accuracy;
  // Its own per-vertex field is the one to show (FieldMode::texels) unless
  // --field asks for another: the pixmap method's texels.
  bool texel_field = false;
};

// The table. The first entry is the default method.
const std::vector<Method>& methods();
// The method called `name`; InputError listing the names otherwise.
const Method& find_method(const std::string& name);

// Every method's options, each name once (first declaration), with the
// methods that take it: for a CLI that registers them all.
std::vector<std::pair<OptionSpec, std::vector<std::string>>> all_method_options();

// Checks `given` against the method (InputError for an option the method
// does not take, naming the methods that do), solves, and makes the field
// of options.field (compute_field): with gather, solution.nodal is replaced,
// `field` says how, and "direct" and "gather" join `seconds`; "setup" (first)
// is the wall time of the solve its own phases leave out.
MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const OptionValues& given = {}, const SolveCallbacks& callbacks = {});

}  // namespace radmesh
