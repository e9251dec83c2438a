// The option machinery's text side: flags, defaults as text, parsing and
// range checks, shared by every OptionTable.

#include "radmesh/options.h"

#include "core/text_syntax.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace radmesh {

std::string option_flag(const std::string& name) {
  std::string f = "--" + name;
  std::replace(f.begin(), f.end(), '_', '-');
  return f;
}

std::string OptionSpec::flag() const { return option_flag(name); }

std::string OptionSpec::default_text() const {
  switch (kind) {
    case Kind::choice: return choices.empty() ? std::string() : choices.front();
    case Kind::flag: return default_value != 0.0 ? "true" : "false";
    case Kind::integer: return std::to_string(static_cast<long long>(default_value));
    case Kind::real: return format_number(default_value);
  }
  return {};
}

namespace {

[[noreturn]] void bad_value(const OptionSpec& s, const std::string& text, const std::string& owner,
                            const std::string& why) {
  throw InputError(s.name + " " + text + " (" + owner + "): " + why, {s.name});
}

// A number's checks, with the text it was read from for the message.
void check_number(const OptionSpec& s, double v, const std::string& text, const std::string& owner) {
  switch (s.kind) {
    case OptionSpec::Kind::flag:
      if (v != 0.0 && v != 1.0) bad_value(s, text, owner, "expected true or false");
      return;
    case OptionSpec::Kind::choice:
      if (!(v >= 0.0 && v < static_cast<double>(s.choices.size()))) bad_value(s, text, owner, "not one of its choices");
      return;
    case OptionSpec::Kind::integer:
    case OptionSpec::Kind::real:
      if (!std::isfinite(v)) bad_value(s, text, owner, "not a finite number");
      if (s.kind == OptionSpec::Kind::integer && v != std::floor(v)) bad_value(s, text, owner, "not an integer");
      if (v < s.min || v > s.max)
        bad_value(s, text, owner,
                  "out of range [" + format_number(s.min) + ", " + format_number(s.max) + "]" +
                      (s.unit.empty() ? "" : " " + s.unit));
      return;
  }
}

}  // namespace

void check_option(const OptionSpec& s, double v, const std::string& owner) {
  check_number(s, v, format_number(v), owner);
}

double parse_option(const OptionSpec& s, const std::string& text, const std::string& owner) {
  switch (s.kind) {
    case OptionSpec::Kind::flag:
      if (text == "true" || text == "1" || text.empty()) return 1.0;
      if (text == "false" || text == "0") return 0.0;
      bad_value(s, text, owner, "expected true or false");
    case OptionSpec::Kind::choice: {
      const auto it = std::find(s.choices.begin(), s.choices.end(), text);
      if (it == s.choices.end()) {
        std::string list;
        for (const std::string& c : s.choices) list += (list.empty() ? "" : ", ") + c;
        bad_value(s, text, owner, "expected one of " + list);
      }
      return static_cast<double>(it - s.choices.begin());
    }
    case OptionSpec::Kind::integer:
    case OptionSpec::Kind::real: {
      double v = 0.0;
      const std::string why = internal::read_number(text, &v);
      if (!why.empty()) bad_value(s, text, owner, "the value " + why);
      check_number(s, v, text, owner);
      return v;
    }
  }
  return 0.0;
}

void unknown_option(const std::string& name, const std::string& owner) {
  throw InputError(name + " is not an option of " + owner, {name});
}

}  // namespace radmesh
