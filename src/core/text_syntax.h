// Internal: the one number syntax of radmesh's text formats (OBJ, MTL,
// ASCII PLY, OFF, ASCII STL, probe files) and of option values, read by one
// parser, and the check that a third-party parser (tinyobjloader, assimp)
// read a number as its text means. A reader refuses, at its line, a token
// outside the syntax, and a token that its format's parser reads otherwise;
// so the value checked is the value used. docs/scenes.md lists what each
// format takes.
#pragma once

#include <string>
#include <string_view>

namespace radmesh::internal {

// The longest number token read (a longer one is refused: no exporter
// writes one, and tinyobjloader reads 330 digits as 0).
inline constexpr size_t kMaxNumberChars = 100;

// Reads `token` as a decimal number of the syntax
//   -?(D+(.D*)?|.D+)([eE][+-]?D+)?     (D: a digit)
// of at most kMaxNumberChars characters whose value is finite in double
// (one below the smallest double reads as 0). Not read: hexadecimal
// (0x1p0), nan and inf in any spelling, a leading '+', a decimal comma.
// Stores the correctly rounded value and returns ""; otherwise returns why
// not, as a phrase after the token ("is hexadecimal, ...").
std::string read_number(std::string_view token, double* value);

// Reads `token` as a whole number -?D+ of at most 18 digits (no '-' unless
// allow_negative); returns "" or why not.
std::string read_whole(std::string_view token, bool allow_negative, long long* value);

// Whether a parser that read `used` for a token meaning `meant` read it
// as it means, at the precision it keeps: within 1e-12 of it (or of the
// smallest normal double) in double; within 4e-6 of it (32 units in the
// last place, or the smallest normal float) in float, whose parsers
// round in several steps.
bool reads_as_double(double used, double meant);
bool reads_as_float(double used, double meant);

// Text from a file as a message may show it: control bytes as \xNN, at
// most `most` characters, then "..." and its length.
std::string shown(std::string_view text, size_t most = 40);

// Removes a UTF-8 byte-order mark from the start of `text`; says whether it had one.
bool strip_byte_order_mark(std::string& text);

}  // namespace radmesh::internal
