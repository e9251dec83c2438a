// radmesh typed errors. The library throws these and never prints or exits;
// the CLI catches them once and prints their message on one line.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace radmesh {

// Base of every radmesh error. A message that names an option names it as
// its options struct does (`max_edge`, `epsilon`): options() lists those
// names, so that a front end can show them as it spells them (the radmesh
// program writes --max-edge, --epsilon).
class Error : public std::runtime_error {
public:
  explicit Error(const std::string& message, std::vector<std::string> options = {})
      : std::runtime_error(message), options_(std::move(options)) {}
  const std::vector<std::string>& options() const noexcept { return options_; }

private:
  std::vector<std::string> options_;
};

// The input (scene file, probe file, options) is malformed or out of range.
// The message names the file, the line and the offending value.
class InputError : public Error {
public:
  using Error::Error;
};

// Geometry that cannot be processed (degenerate polygon, failed triangulation).
class GeometryError : public Error {
public:
  using Error::Error;
};

// A numerical problem: non-convergence, NaN, a system too large for memory.
class NumericalError : public Error {
public:
  using Error::Error;
};

// Reading or writing a file failed.
class IoError : public Error {
public:
  using Error::Error;
};

// Helper: "file:line: " prefix (line omitted when <= 0, file omitted when empty).
std::string where(const std::string& file, int line);

// The same place without the ": ", in parentheses after a space, for a
// second place inside a message (" (file:line)"; empty when file is empty).
std::string also_at(const std::string& file, int line);

// A number for a message: up to 9 significant digits, no trailing zeros
// (std::to_string would print 1e-20 as 0.000000).
std::string format_number(double v);

}  // namespace radmesh
