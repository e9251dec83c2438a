// Helpers for error messages: a place ("file:line: "), a second place in
// a message, and numbers written short.

#include "radmesh/errors.h"

#include <sstream>

namespace radmesh {

std::string where(const std::string& file, int line) {
  std::string s;
  s.append(file);
  if (line > 0) {
    s.push_back(':');
    s.append(std::to_string(line));
  }
  if (!s.empty()) s.append(": ");
  return s;
}

std::string also_at(const std::string& file, int line) {
  std::string s = where(file, line);
  if (s.empty()) return s;
  s.resize(s.size() - 2);  // without its ": "
  return " (" + s + ")";
}

std::string format_number(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

}  // namespace radmesh
