// Options declared once: each option of an options struct (a method's, the
// solve's, the meshing's) is one entry of an OptionTable that binds its name,
// unit, help, range and default to the struct's member. The table checks a
// struct (the library's entry points), reads text values into one (the
// radmesh program, the benchmark), and lists the values for summaries; the
// range is the same on every path.
//
// A name is the struct member's, and the program's flag is that name with
// '_' written '-' after "--" (option_flag): errors name options by name
// (Error::options), and the program shows them as flags.
#pragma once

#include "radmesh/errors.h"

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace radmesh {

struct OptionSpec {
  enum class Kind { real, integer, choice, flag };
  std::string name;
  Kind kind = Kind::real;
  std::string unit;   // "" when dimensionless
  std::string help;   // one sentence, without the default
  double default_value = 0.0;  // real, integer, flag (0 or 1); choice: 0 (the first choice)
  double min = 0.0, max = 0.0;  // inclusive range (real, integer)
  std::vector<std::string> choices;  // choice: the accepted values, the default first

  std::string flag() const;  // "--min-area"
  std::string default_text() const;
};

// "--" + name with '_' written '-': the command-line flag of an option.
std::string option_flag(const std::string& name);

// Option values as text (name -> text, e.g. from the command line).
using OptionValues = std::map<std::string, std::string>;

// One option's value, for summaries: `number` for every kind (a choice's
// index, a flag's 0 or 1), `text` as the option would be written.
struct OptionValue {
  std::string name;
  OptionSpec::Kind kind = OptionSpec::Kind::real;
  double number = 0.0;
  std::string text;
};

// Parses `text` as `spec` wants and checks its range. InputError naming the
// option (Error::options) and the value otherwise; `owner` says whose option
// it is in the message ("method hierarchical").
double parse_option(const OptionSpec& spec, const std::string& text, const std::string& owner);
// Checks a number against `spec`'s range (finite, an integer where the kind
// says so). Same errors as parse_option.
void check_option(const OptionSpec& spec, double value, const std::string& owner);
// InputError for an option name that `specs` lacks.
[[noreturn]] void unknown_option(const std::string& name, const std::string& owner);

template <class Options>
class OptionTable {
public:
  explicit OptionTable(std::string owner) : owner_(std::move(owner)) {}

  OptionTable& real(std::string name, double Options::*member, std::string unit, std::string help, double min,
                    double max) {
    return add({std::move(name), OptionSpec::Kind::real, std::move(unit), std::move(help), 0.0, min, max, {}},
               [member](const Options& o) { return o.*member; },
               [member](Options& o, double v) { o.*member = v; });
  }
  template <class Int>
  OptionTable& integer(std::string name, Int Options::*member, std::string unit, std::string help, double min,
                       double max) {
    return add({std::move(name), OptionSpec::Kind::integer, std::move(unit), std::move(help), 0.0, min, max, {}},
               [member](const Options& o) { return static_cast<double>(o.*member); },
               [member](Options& o, double v) { o.*member = static_cast<Int>(v); });
  }
  OptionTable& flag(std::string name, bool Options::*member, std::string help) {
    return add({std::move(name), OptionSpec::Kind::flag, "", std::move(help), 0.0, 0.0, 1.0, {}},
               [member](const Options& o) { return o.*member ? 1.0 : 0.0; },
               [member](Options& o, double v) { o.*member = v != 0.0; });
  }
  // `values`: (name, value) of each choice; the default's name comes first
  // in the declaration, the others in the order given.
  template <class E>
  OptionTable& choice(std::string name, E Options::*member, std::string help,
                      std::vector<std::pair<std::string, E>> values) {
    const E standard = Options{}.*member;
    std::stable_partition(values.begin(), values.end(), [&](const auto& v) { return v.second == standard; });
    OptionSpec spec{std::move(name), OptionSpec::Kind::choice, "", std::move(help), 0.0, 0.0, 0.0, {}};
    std::vector<E> order;
    for (const auto& [n, v] : values) {
      spec.choices.push_back(n);
      order.push_back(v);
    }
    return add(std::move(spec),
               [member, order](const Options& o) {
                 for (size_t k = 0; k < order.size(); ++k)
                   if (order[k] == o.*member) return static_cast<double>(k);
                 return -1.0;
               },
               [member, order](Options& o, double v) { o.*member = order.at(static_cast<size_t>(v)); });
  }
  // An option that reads and writes the struct through functions (a member
  // of a member).
  OptionTable& add(OptionSpec spec, std::function<double(const Options&)> get,
                   std::function<void(Options&, double)> set) {
    spec.default_value = get(Options{});
    specs_.push_back(std::move(spec));
    get_.push_back(std::move(get));
    set_.push_back(std::move(set));
    return *this;
  }

  const std::vector<OptionSpec>& specs() const { return specs_; }
  const std::string& owner() const { return owner_; }

  // InputError naming the first member out of its range.
  void check(const Options& o) const {
    for (size_t k = 0; k < specs_.size(); ++k) check_option(specs_[k], get_[k](o), owner_);
  }
  // `o` with the given text values read into it (each checked); InputError
  // for a name the table lacks.
  void apply(Options& o, const OptionValues& given) const {
    for (const auto& [name, text] : given) {
      const size_t k = index(name);
      set_[k](o, parse_option(specs_[k], text, owner_));
    }
  }
  Options parse(const OptionValues& given) const {
    Options o;
    apply(o, given);
    check(o);
    return o;
  }
  // Every option's value in `o`, in declaration order.
  std::vector<OptionValue> values(const Options& o) const {
    std::vector<OptionValue> out;
    for (size_t k = 0; k < specs_.size(); ++k) {
      const OptionSpec& s = specs_[k];
      OptionValue v{s.name, s.kind, get_[k](o), {}};
      switch (s.kind) {
        case OptionSpec::Kind::choice: v.text = v.number >= 0 ? s.choices[static_cast<size_t>(v.number)] : "?"; break;
        case OptionSpec::Kind::flag: v.text = v.number != 0.0 ? "true" : "false"; break;
        default: v.text = format_number(v.number);
      }
      out.push_back(std::move(v));
    }
    return out;
  }
  // The names whose values in `o` differ from the defaults.
  std::vector<std::string> changed(const Options& o) const {
    std::vector<std::string> out;
    for (size_t k = 0; k < specs_.size(); ++k)
      if (get_[k](o) != specs_[k].default_value) out.push_back(specs_[k].name);
    return out;
  }
  bool has(const std::string& name) const {
    for (const OptionSpec& s : specs_)
      if (s.name == name) return true;
    return false;
  }

private:
  size_t index(const std::string& name) const {
    for (size_t k = 0; k < specs_.size(); ++k)
      if (specs_[k].name == name) return k;
    unknown_option(name, owner_);
  }

  std::string owner_;
  std::vector<OptionSpec> specs_;
  std::vector<std::function<double(const Options&)>> get_;
  std::vector<std::function<void(Options&, double)>> set_;
};

}  // namespace radmesh
