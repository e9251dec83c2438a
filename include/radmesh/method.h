// The solver contract: every radiosity method is one entry of one table,
// with its declared options, its recommended initial meshing and a solve
// that returns a result on its own mesh with named counters. The radmesh
// program, the summary, the benchmark and the conformance tests loop over
// this table and know no method by name or type.
//
// Adding a method: write its solver in its own folder (a one-off solve_x()
// and, where state lives between calls, a solver class) and a method.cpp
// whose make_x_method() declares its options (an OptionTable over its
// options struct) and adapts its result; then add its line to methods() in
// src/radiosity/methods/methods.cpp. A program may also add_method() its own.
#pragma once

#include "radmesh/field.h"
#include "radmesh/mesh.h"
#include "radmesh/options.h"
#include "radmesh/progress.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

namespace radmesh {

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
// NAME.vtu by the radmesh program.
struct LineSet {
  std::vector<std::array<Vec3, 2>> segments;
  std::vector<std::pair<std::string, std::vector<int>>> int_fields;
  std::vector<std::pair<std::string, std::vector<double>>> real_fields;
};

// A method's saved state, opaque to all but the method that reads it
// (Method::read_state) and continues from it (SolveCallbacks::resume).
class MethodState {
public:
  virtual ~MethodState() = default;
  std::string source;  // where it was read from, for messages
};

// Files a result writes beside the common ones (its saved state, its
// lightmaps): their names in the output directory, and the writer, which
// returns the paths it wrote. Throws IoError.
struct MethodFiles {
  std::vector<std::string> names;
  std::function<std::vector<std::string>(const std::string& out_dir, const Mesh& mesh)> write;
};

// What a method returns: a solution on its own mesh (the initial mesh, or
// one it refined), extra per-triangle integer fields for the .vtu, extra
// line sets, counters and the wall time of its phases. It owns everything
// it refers to: it may outlive the scene and mesh it was made from.
struct MethodResult {
  Mesh mesh;
  Solution solution;  // per triangle of `mesh` and per vertex; common counts in solution.stats
  std::vector<std::pair<std::string, std::vector<int>>> cell_fields;
  std::vector<std::pair<std::string, LineSet>> line_sets;  // (file stem, lines)
  std::vector<Counter> counters;
  std::vector<std::pair<std::string, double>> seconds;  // phase -> wall seconds, in order
  std::string report;  // one line for people ("24128 leaves, 493567 links, ...")
  FieldReport field;   // how solution.nodal was made (run_method)
  MethodFiles files;   // none for most methods
  bool interrupted = false;  // stopped early by SolveCallbacks::cancelled
  std::string progress;      // how far an interrupted run got, for people ("120 shots")
  // What the result says is likely wrong with the scene (run_method): no
  // light reached any surface that reflects.
  std::vector<std::string> warnings;

  const Counter* counter(const std::string& name) const;  // nullptr when absent
};

struct SolveCallbacks {
  ProgressFn progress;
  // Called after every refinement round of a method that has rounds (or
  // every so many steps of a progressive one), with the result as it then
  // stands (for a series of files).
  std::function<void(const MethodResult&, int round)> on_round;
  // Polled by methods that can stop early and still return a consistent
  // result (Method::resumable): true stops them (MethodResult::interrupted).
  std::function<bool()> cancelled;
  // A saved state to continue from (Method::read_state's).
  std::shared_ptr<const MethodState> resume;
};

// The option values a method solves with: its own options struct, held
// without its type, and the list of values for summaries.
class MethodOptions {
public:
  MethodOptions() = default;
  template <class Options>
  MethodOptions(Options value, std::vector<OptionValue> values)
      : value_(std::make_shared<const Options>(std::move(value))), type_(&typeid(Options)),
        values_(std::move(values)) {}
  // `value` checked against its table (InputError naming the first option
  // out of range), with its values listed.
  template <class Options>
  static MethodOptions checked(const OptionTable<Options>& table, Options value) {
    table.check(value);
    std::vector<OptionValue> values = table.values(value);
    return MethodOptions(std::move(value), std::move(values));
  }
  // The options struct; InputError when it holds another type (options of
  // another method).
  template <class Options>
  const Options& get() const {
    if (!value_ || *type_ != typeid(Options)) throw InputError("the options given are not this method's");
    return *static_cast<const Options*>(value_.get());
  }
  const std::vector<OptionValue>& values() const { return values_; }

private:
  std::shared_ptr<const void> value_;
  const std::type_info* type_ = nullptr;
  std::vector<OptionValue> values_;
};

// A named set of option values (solve, meshing and the method's own, by
// name) that a user can reason about: `draft` for a quick look, `fine` for
// a closer answer, each with its measured error and time in
// docs/methods.md. `default` is the options' defaults.
struct Preset {
  std::string name;
  std::string help;  // what it trades, one line
  OptionValues values;
};
// The preset names every method answers to, in order.
inline const std::vector<std::string>& preset_names() {
  static const std::vector<std::string> names = {"draft", "default", "fine"};
  return names;
}

struct Method {
  std::string name;
  std::string help;  // one sentence for --help
  std::vector<OptionSpec> options;
  // Reads option values given as text into the method's options (checked);
  // the others take their defaults.
  std::function<MethodOptions(const OptionValues&)> parse;
  // The initial meshing this method works best from: the radmesh program
  // and the bench start from these and apply what the user gave on top.
  std::function<MeshingOptions(const Scene&)> meshing;
  std::function<MethodResult(const Scene&, const Mesh&, const SolveOptions&, const MethodOptions&,
                             const SolveCallbacks&)>
      solve;
  // Options of the solve and of the meshing (by name: solve_option_table,
  // meshing_option_table) that the method does not use: giving one is an
  // error (check_shared_options).
  std::vector<std::string> unused;
  // A method that stops on SolveCallbacks::cancelled and continues from a
  // saved state reads the state a run saved in its output directory here
  // (IoError, InputError naming the file). Empty for the others.
  std::function<std::shared_ptr<const MethodState>(const std::string& out_dir)> read_state;
  bool resumable() const { return static_cast<bool>(read_state); }
  // The name of the method's own per-vertex field, which stands unless
  // SolveOptions::field asks for another (FieldMode::own); "" for none.
  std::string own_field;
  // Every file name its results' MethodFiles may hold (for clearing an
  // output directory of an earlier run's).
  std::vector<std::string> files;
  // Its presets other than `default` (draft and fine; see preset_names).
  std::vector<Preset> presets;
};

// The table. The first entry is the default method.
const std::deque<Method>& methods();
// The method called `name`; InputError listing the names otherwise.
const Method& find_method(const std::string& name);
// Adds a method at the end of the table (a program's own method; the
// conformance tests run every method of the table). Not thread-safe: call it
// before solving. InputError when the name is taken.
void add_method(Method method);

// Every method's options, each name once (first declaration), with the
// methods that take it: for a front end that registers them all.
std::vector<std::pair<OptionSpec, std::vector<std::string>>> all_method_options();

// `given` read for `method` (Method::parse): InputError for an option the
// method does not take, naming the methods that do.
MethodOptions method_options(const Method& method, const OptionValues& given);

// Adds the values of `method`'s preset `preset` to the options given by
// name (of the solve, of the meshing, of the method) where they are not
// given: an option named by the user wins over the preset. InputError
// naming the presets when `preset` is none of them.
void apply_preset(const Method& method, const std::string& preset, OptionValues& solve, OptionValues& meshing,
                  OptionValues& method_given);

// InputError naming the first of `given` (options of the solve or the
// meshing, by name) that `method` does not use. `field` is the field asked
// for: the gather casts shadow rays, so `rays` is used with it.
void check_shared_options(const Method& method, const std::vector<std::string>& given, FieldMode field);

// The state a run of `method` saved in `out_dir` (Method::read_state), to
// continue from (SolveCallbacks::resume). InputError naming the methods
// that can resume when `method` cannot.
std::shared_ptr<const MethodState> read_method_state(const Method& method, const std::string& out_dir);

// Solves and makes the field of options.field (compute_field): with gather,
// solution.nodal is replaced, `field` says how, and "direct" and "gather"
// join `seconds`; "setup" (first) is the wall time of the solve its own
// phases leave out.
MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const MethodOptions& method_options, const SolveCallbacks& callbacks = {});
// The same with option values as text (method_options(method, given)).
MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const OptionValues& given = {}, const SolveCallbacks& callbacks = {});

// Builds a table entry from a method's OptionTable and its typed solve.
template <class Options>
Method make_method(std::string name, std::string help, const OptionTable<Options>& table,
                   std::function<MethodResult(const Scene&, const Mesh&, const SolveOptions&, const Options&,
                                              const SolveCallbacks&)>
                       solve) {
  Method m;
  m.name = std::move(name);
  m.help = std::move(help);
  m.options = table.specs();
  m.parse = [table](const OptionValues& given) { return MethodOptions::checked(table, table.parse(given)); };
  m.solve = [solve = std::move(solve)](const Scene& scene, const Mesh& mesh, const SolveOptions& so,
                                       const MethodOptions& mo, const SolveCallbacks& cb) {
    return solve(scene, mesh, so, mo.get<Options>(), cb);
  };
  return m;
}

}  // namespace radmesh
