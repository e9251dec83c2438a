// The checks a PLY, OFF or STL file passes before assimp reads it
// (mesh_checks.h): counts within what the file holds, nothing past what
// they declare, every line of a text body as its format says, and every
// number in radmesh's syntax and read by assimp's parser as its text means.

#include "io/readers/mesh_checks.h"

#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <assimp/defs.h>
#include <assimp/fast_atof.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace radmesh::internal {

namespace {

namespace fs = std::filesystem;

// "1 face", "2 faces"; "1 vertex", "3 vertices" with `many` given.
std::string plural(double n, const std::string& one, const std::string& many = "") {
  return format_number(n) + " " + (n == 1.0 ? one : many.empty() ? one + "s" : many);
}

// Splits a line at spaces and tabs.
void split(std::string_view line, std::vector<std::string_view>* out) {
  out->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) out->push_back(line.substr(b, i - b));
  }
}

// "" or why a line of a text body cannot be read as it is: a control
// character (assimp ends a line at \r, \f and NUL, and splits a line at
// spaces and tabs only).
std::string control_character(std::string_view line) {
  for (const char c : line)
    if (static_cast<unsigned char>(c) < 0x20 && c != '\t') {
      char code[40];
      std::snprintf(code, sizeof code, "control character 0x%02X in the line",
                    static_cast<unsigned>(static_cast<unsigned char>(c)));
      return code;
    }
  return "";
}

// Reads a line, without its '\r' before the '\n'; counts it.
bool next_line(std::istream& in, std::string* line, int* ln) {
  if (!std::getline(in, *line)) return false;
  ++*ln;
  if (!line->empty() && line->back() == '\r') line->pop_back();
  return true;
}

bool blank(std::string_view line) { return line.find_first_not_of(" \t") == std::string_view::npos; }

// What assimp's number parser throws here (its own exception type is not
// exported by the shared library); the parse is the same.
struct NotReadByAssimp : std::runtime_error {
  template <class... Args>
  explicit NotReadByAssimp(Args&&...) : std::runtime_error("not a number to assimp") {}
};

// A value of a text format assimp reads: in radmesh's syntax, and read by
// assimp's parser (fast_atoreal_move into Real; positions are floats) as
// its text means. Returns "" or why not.
template <class Real>
std::string assimp_number(std::string_view token, double* meant) {
  std::string why = read_number(token, meant);
  if (!why.empty()) return why;
  // assimp's parser reads a run of more than 19 digits as 0, saying so in
  // its log: such a run is refused here without calling it (the log is
  // global, and another thread's import may be creating or destroying it).
  size_t run = 0, longest = 0;
  for (const char c : token) {
    run = c >= '0' && c <= '9' ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  if (longest > 19)
    return "has a run of " + std::to_string(longest) +
           " digits; assimp's parser reads more than 19 in a row as 0 (write it with fewer digits, or in exponent "
           "notation)";
  char text[kMaxNumberChars + 1];
  std::memcpy(text, token.data(), token.size());
  text[token.size()] = '\0';
  Real got = 0;
  const char* end = text;
  try {
    end = Assimp::fast_atoreal_move<Real, NotReadByAssimp>(text, got);
  } catch (const std::exception&) {
    return "is not read by assimp's number parser";
  }
  const double wide = static_cast<double>(got);
  const double used = std::abs(wide) <= FLT_MAX ? static_cast<double>(static_cast<float>(wide)) : wide * INFINITY;
  if (end != text + token.size() || !reads_as_float(used, *meant))
    return "means " + format_number(*meant) + ", but assimp's parser reads it as " + format_number(used) +
           " (it reads 19 digits before the point, 15 after it, and floats up to 3.4e38): write it with fewer "
           "digits, or in exponent notation";
  return "";
}

// ------------------------------------------------------------------ PLY

enum class Kind { signed_whole, unsigned_whole, real };

struct PlyType {
  std::string name;
  int bytes = 0;
  Kind kind = Kind::real;
  double lo = 0.0, hi = 0.0;  // whole types: the range
};

const PlyType* ply_type(const std::string& name) {
  static const std::map<std::string, PlyType> types = [] {
    std::map<std::string, PlyType> t;
    auto add = [&](std::initializer_list<const char*> names, int bytes, Kind kind, double lo, double hi) {
      for (const char* n : names) t[n] = {n, bytes, kind, lo, hi};
    };
    add({"char", "int8"}, 1, Kind::signed_whole, -128, 127);
    add({"uchar", "uint8"}, 1, Kind::unsigned_whole, 0, 255);
    add({"short", "int16"}, 2, Kind::signed_whole, -32768, 32767);
    add({"ushort", "uint16"}, 2, Kind::unsigned_whole, 0, 65535);
    add({"int", "int32"}, 4, Kind::signed_whole, -2147483648.0, 2147483647.0);
    add({"uint", "uint32"}, 4, Kind::unsigned_whole, 0, 4294967295.0);
    add({"float", "float32"}, 4, Kind::real, 0, 0);
    add({"double", "float64"}, 8, Kind::real, 0, 0);
    return t;
  }();
  const auto it = types.find(name);
  return it == types.end() ? nullptr : &it->second;
}

struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType type;        // a value's (a list's items')
  PlyType count_type;  // a list's count
};

struct PlyElement {
  std::string name;
  double count = 0.0;
  std::vector<PlyProperty> properties;
};

// What a PLY header declares, and where it ends.
struct PlyHeader {
  bool binary = false, big_endian = false;
  double bytes_needed = 0.0;  // at least, for the declared elements
  std::vector<PlyElement> elements;
  size_t read = 0;  // bytes of the header
  int ln = 0;       // lines of the header
};

double element_total(const PlyHeader& h) {
  double n = 0.0;
  for (const PlyElement& e : h.elements) n += e.count;
  return n;
}

// Reads a PLY header: known keywords and types only, end_header within the
// first 64 KiB (assimp 5.2 loops without end on some malformed headers: an
// unknown property type, no end_header), whole-number list counts, a
// vertex element with x, y and z. Throws InputError naming the header line.
PlyHeader read_ply_header(std::istream& in, const std::string& path) {
  auto bad = [&](int line, const std::string& what) {
    throw InputError(path + ": PLY header line " + std::to_string(line) + ": " + what);
  };
  PlyHeader h;
  bool ended = false;
  std::string line;
  while (!ended && h.read < 65536 && std::getline(in, line)) {
    h.read += line.size() + 1;
    ++h.ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    const std::string head = w.empty() ? "" : w[0];
    if (h.ln == 1) {
      if (head != "ply" || w.size() != 1) bad(1, "a PLY file starts with the line 'ply'");
    } else if (head == "format") {
      if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        bad(h.ln, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      h.binary = w[1] != "ascii";
      h.big_endian = w[1] == "binary_big_endian";
    } else if (head == "comment" || head == "obj_info") {
    } else if (head == "element") {
      long long count = -1;
      if (w.size() != 3 || !read_whole(w[2], false, &count).empty())
        bad(h.ln, "expected 'element NAME COUNT' with a whole COUNT >= 0");
      h.elements.push_back({w[1], static_cast<double>(count), {}});
    } else if (head == "property") {
      const bool list = w.size() == 5 && w[1] == "list";
      if (!(list || w.size() == 3)) bad(h.ln, "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      for (size_t i = list ? 2 : 1; i + 1 < w.size(); ++i)
        if (!ply_type(w[i])) bad(h.ln, "unknown property type '" + shown(w[i]) + "'");
      if (h.elements.empty()) bad(h.ln, "'property' before any 'element'");
      PlyProperty p;
      p.name = w.back();
      p.list = list;
      p.type = *ply_type(w[list ? 3 : 1]);
      if (list) {
        p.count_type = *ply_type(w[2]);
        if (p.count_type.kind == Kind::real)
          bad(h.ln, "a list's count of type '" + w[2] + "', not a whole-number type");
      }
      PlyElement& e = h.elements.back();
      for (const PlyProperty& q : e.properties)
        if (q.name == p.name)
          bad(h.ln, "property '" + shown(p.name) + "' of element '" + shown(e.name) +
                        "' declared again (assimp would read one of the two)");
      e.properties.push_back(p);
    } else if (head == "end_header") {
      ended = true;
    } else {
      bad(h.ln, "unexpected '" + shown(line) + "'");
    }
  }
  if (!ended) bad(h.ln, "no end_header line in the first 64 KiB");
  // At least one byte per value in binary (its count's, for a list), two
  // in ASCII (a digit and a separator).
  for (const PlyElement& e : h.elements) {
    double bytes = 0.0;
    for (const PlyProperty& p : e.properties) bytes += h.binary ? (p.list ? p.count_type.bytes : p.type.bytes) : 2.0;
    h.bytes_needed += e.count * bytes;
  }
  const auto vertex = std::find_if(h.elements.begin(), h.elements.end(),
                                   [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == h.elements.end() || vertex->count == 0.0)
    throw InputError(path + ": the PLY header declares no vertices (" +
                     (vertex == h.elements.end() ? std::string("no 'element vertex'") : "'element vertex 0'") +
                     "): the file has no vertices");
  for (const char* axis : {"x", "y", "z"})
    if (std::none_of(vertex->properties.begin(), vertex->properties.end(),
                     [&](const PlyProperty& p) { return p.name == axis && !p.list; }))
      throw InputError(path + ": the PLY header's element vertex has no property " + axis +
                       " (assimp would read it as 0)");
  return h;
}

// Data after the declared elements is a wrong count whose rest assimp
// drops without a word (a header declaring 1 face over a file of 2 gives
// one triangle, half the square).
[[noreturn]] void more_than_declared(const std::string& path, const PlyHeader& header, const std::string& what) {
  throw InputError(path + ": " + what + " after the " + plural(element_total(header), "element") +
                   " its PLY header declares (a wrong count would drop them)");
}

// A binary body's length, walking its lists in one pass (a list's count
// read in the file's byte order and type): a list longer than the rest of
// the file is refused before assimp allocates it (a 280-byte file whose
// face claimed 2^26 vertices took 564 MB), and anything past the declared
// elements is more than declared.
void check_binary_ply_body(std::istream& in, const std::string& path, const PlyHeader& header, double file_size) {
  double at = static_cast<double>(header.read);
  unsigned char count[8] = {};
  for (const PlyElement& e : header.elements) {
    const bool has_list =
        std::any_of(e.properties.begin(), e.properties.end(), [](const PlyProperty& p) { return p.list; });
    if (!has_list) {
      double fixed = 0.0;
      for (const PlyProperty& p : e.properties) fixed += p.type.bytes;
      at += e.count * fixed;
      if (at > file_size)
        throw InputError(path + ": the " + plural(e.count, e.name) + " its PLY header declares end at byte " +
                         format_number(at) + ", past the file's " + format_number(file_size) + " (truncated)");
      in.seekg(static_cast<std::streamoff>(at));
      continue;
    }
    for (double k = 0.0; k < e.count; ++k)
      for (const PlyProperty& p : e.properties) {
        // The element named in a message (built only when one is thrown).
        auto which = [&] { return e.name + " " + format_number(k); };
        if (!p.list) {
          in.ignore(p.type.bytes);
          at += p.type.bytes;
          continue;
        }
        const int cb = p.count_type.bytes;
        if (at + cb > file_size || !in.read(reinterpret_cast<char*>(count), cb))
          throw InputError(path + ": " + which() + ": the file ends before its list count (truncated)");
        uint64_t raw = 0;
        for (int b = 0; b < cb; ++b)
          raw |= static_cast<uint64_t>(count[header.big_endian ? cb - 1 - b : b]) << (8 * b);
        double items = static_cast<double>(raw);
        if (p.count_type.kind == Kind::signed_whole && (raw >> (8 * cb - 1)) != 0)
          items -= std::ldexp(1.0, 8 * cb);  // two's complement
        if (items < 0.0)
          throw InputError(path + ": " + which() + ": a list count of " + format_number(items) + " in property '" +
                           shown(p.name) + "'");
        const double bytes = items * p.type.bytes, left = file_size - at - cb;
        if (bytes > left)
          throw InputError(path + ": " + which() + ": a list of " + format_number(items) + " values of " +
                           std::to_string(p.type.bytes) + " bytes in property '" + shown(p.name) + "' needs " +
                           format_number(bytes) + " bytes, but the file has " + format_number(left) +
                           " bytes left (a wrong count, or a truncated file)");
        at += cb + bytes;
        in.ignore(static_cast<std::streamsize>(bytes));
      }
  }
  if (file_size > at) more_than_declared(path, header, format_number(file_size - at) + " bytes");
}

// "" or why `token` is not a value of type `t` as assimp reads it (whole
// types with strtoul10/strtol10, which wrap past 32 bits and stop at a
// sign they do not take; real types with fast_atoreal_move).
std::string ply_value(std::string_view token, const PlyType& t, long long* whole) {
  if (t.kind == Kind::real) {
    double meant = 0.0;
    return t.bytes == 8 ? assimp_number<double>(token, &meant) : assimp_number<ai_real>(token, &meant);
  }
  std::string why = read_whole(token, t.kind == Kind::signed_whole, whole);
  if (!why.empty()) return why;
  if (static_cast<double>(*whole) < t.lo || static_cast<double>(*whole) > t.hi)
    return "is outside the range of its type " + t.name + " (" + format_number(t.lo) + " to " + format_number(t.hi) +
           ")";
  return "";
}

// An ASCII body has one line per element, holding exactly the values its
// properties declare (assimp reads a missing value as 0 and drops extra
// ones), each a number of its type's syntax, a list's count no more than
// the values left on its line (assimp allocates what a count says); fewer
// lines is a truncated file, more is a wrong count.
void check_ascii_ply_body(std::istream& in, const std::string& path, const PlyHeader& header) {
  int ln = header.ln;
  std::string line;
  const double elements = element_total(header);
  double vertices = 0.0;
  for (const PlyElement& e : header.elements)
    if (e.name == "vertex") vertices = e.count;
  double lines = 0.0;
  std::vector<std::string_view> tokens;
  for (const PlyElement& e : header.elements)
    for (double k = 0.0; k < e.count; ++k) {
      do {
        if (!next_line(in, &line, &ln))
          throw InputError(path + ": the PLY header declares " + plural(elements, "element") + ", but the file has " +
                           plural(lines, "line") + " after its header (truncated, or a wrong count)");
      } while (blank(line));
      ++lines;
      auto bad = [&](const std::string& what) {
        throw InputError(path + ": line " + std::to_string(ln) + ": " + what);
      };
      if (const std::string c = control_character(line); !c.empty()) bad(c);
      split(line, &tokens);
      size_t at = 0;
      for (const PlyProperty& p : e.properties) {
        if (at >= tokens.size())
          bad(e.name + " " + format_number(k) + " ends before its property '" + shown(p.name) + "' (" +
              plural(static_cast<double>(tokens.size()), "value") + " on the line)");
        long long value = 0;
        if (!p.list) {
          if (const std::string why = ply_value(tokens[at], p.type, &value); !why.empty())
            bad("value '" + shown(tokens[at]) + "' of property '" + shown(p.name) + "' " + why);
          ++at;
          continue;
        }
        // A count beyond the values left on its line is said as such (a
        // long run of digits made assimp 5.2 allocate gigabytes).
        const std::string_view count = tokens[at++];
        const size_t left = tokens.size() - at;
        if (count.find_first_not_of("0123456789") == std::string_view::npos &&
            (count.size() > 18 || std::stod(std::string(count)) > static_cast<double>(left)))
          bad("a list of '" + shown(count) + "' values, but the line has " + std::to_string(left) + " more");
        long long n = 0;
        if (const std::string why = ply_value(count, p.count_type, &n); !why.empty())
          bad("list count '" + shown(count) + "' of property '" + shown(p.name) + "' " + why);
        if (n < 0) bad("a list count of " + std::to_string(n) + " in property '" + shown(p.name) + "'");
        // A face's vertex indices name declared vertices (assimp's check
        // of them names no line).
        const bool indices = e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index");
        for (long long i = 0; i < n; ++i, ++at) {
          if (const std::string why = ply_value(tokens[at], p.type, &value); !why.empty())
            bad("value '" + shown(tokens[at]) + "' in the list of property '" + shown(p.name) + "' " + why);
          if (indices && (value < 0 || static_cast<double>(value) >= vertices))
            bad("vertex index " + std::to_string(value) + " of face " + format_number(k) + " is out of range: the file has " +
                plural(vertices, "vertex", "vertices"));
        }
      }
      if (at < tokens.size())
        bad("'" + shown(tokens[at]) + "' after the values of " + e.name + " " + format_number(k) +
            " (its properties declare " + std::to_string(at) + "; assimp would drop the rest)");
    }
  while (next_line(in, &line, &ln))
    if (!blank(line)) more_than_declared(path, header, "line " + std::to_string(ln) + " holds data");
}

// ------------------------------------------------------------------ OFF

// Bytes at `at` of `path` (fewer at its end).
std::string bytes_at(const std::string& path, double at, size_t n) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(at));
  std::string out(n, '\0');
  in.read(out.data(), static_cast<std::streamsize>(n));
  out.resize(static_cast<size_t>(in.gcount()));
  return out;
}

}  // namespace

// Checks a PLY file before assimp sees it: assimp 5.2 loops without end on
// some malformed headers, and allocates what a header's element counts or
// a list's count declare before reading the body. So: the header as
// read_ply_header says, every element count within what the rest of the
// file can hold (at least one byte per value in binary, two in ASCII),
// every list within the file, every ASCII line as check_ascii_ply_body
// says, and no data past the declared elements.
void check_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto file_size = static_cast<double>(fs::file_size(path, ec));
  const PlyHeader header = read_ply_header(in, path);
  const double body = file_size - static_cast<double>(header.read);
  if (header.bytes_needed > body)
    throw InputError(path + ": the PLY header declares elements needing at least " +
                     std::to_string(static_cast<long long>(std::min(header.bytes_needed, 9e18))) +
                     " bytes, but the file has " + std::to_string(static_cast<long long>(body)) +
                     " after its header (truncated, or a wrong count)");
  if (header.binary)
    check_binary_ply_body(in, path, header, file_size);
  else
    check_ascii_ply_body(in, path, header);
}

// Checks an OFF file as assimp 5.2's OFF reader reads it. The header
// ([ST][C][N][4][n]OFF, the dimension after nOFF, then the vertex, face
// and edge counts, with # comments between) is read as words; the counts
// must be whole numbers the rest of the file can hold (assimp allocates
// them before reading a byte of the body: 3 numbers a vertex, at least 4 a
// face, each at least one character and a separator). The body is read as
// lines: one a vertex with exactly its values (coordinates, w after 4OFF,
// a normal after NOFF, 4 colour values after COFF, 2 texture coordinates
// after STOFF), one a face with its vertex count (3 to 9: assimp's reader
// drops a face of more), that many indices of declared vertices and at
// most 4 colour values; blank lines are skipped, comments and anything
// else are refused, and so is anything but blanks and comments after the
// declared faces (assimp drops it). Throws InputError naming the line.
void check_off(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto file_size = static_cast<double>(fs::file_size(path, ec));
  std::string head(size_t{1} << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  size_t pos = 0;
  int line = 1;
  auto space = [&](size_t i) { return std::isspace(static_cast<unsigned char>(head[i])) != 0; };
  auto next_word = [&] {  // skipping blanks and # comments
    while (pos < head.size()) {
      if (head[pos] == '#') {
        while (pos < head.size() && head[pos] != '\n') ++pos;
      } else if (space(pos)) {
        if (head[pos] == '\n') ++line;
        ++pos;
      } else {
        break;
      }
    }
    const size_t begin = pos;
    while (pos < head.size() && !space(pos) && head[pos] != '#') ++pos;
    return head.substr(begin, pos - begin);
  };
  auto bad = [&](const std::string& what) {
    throw InputError(path + ": OFF header line " + std::to_string(line) + ": " + what);
  };
  const std::string keyword = next_word();
  std::string_view k = keyword;
  auto take = [&](std::string_view prefix) {
    const bool has = k.substr(0, prefix.size()) == prefix;
    if (has) k.remove_prefix(prefix.size());
    return has;
  };
  const bool st = take("ST"), colours = take("C"), normals = take("N"), homogeneous = take("4"),
             dimension = take("n");
  if (k != "OFF") bad("expected the keyword OFF (or [ST][C][N][4][n]OFF), got '" + shown(keyword) + "'");
  long long dimensions = 3;
  if (dimension) {
    const std::string word = next_word();
    if (!read_whole(word, false, &dimensions).empty() || dimensions < 2 || dimensions > 3)
      bad("expected the dimension 2 or 3 after nOFF, got '" + shown(word) + "'");
  }
  auto count = [&] {
    const std::string word = next_word();
    if (word.empty() || word.find_first_not_of("0123456789") != std::string::npos)
      bad("expected the vertex, face and edge counts as whole numbers, got '" + shown(word) + "'");
    return std::strtod(word.c_str(), nullptr);  // within the file's size, or refused below
  };
  const double vertices = count(), faces = count();
  const double numbers = 3.0 * vertices + 4.0 * faces;
  const double body_bytes = file_size - static_cast<double>(pos);
  if (2.0 * numbers - 1.0 > body_bytes)
    bad(format_number(vertices) + " vertices and " + format_number(faces) + " faces need at least " +
        format_number(2.0 * numbers - 1.0) + " bytes, the file has " + format_number(body_bytes) +
        " after the counts (truncated, or a wrong count)");
  count();  // the edge count, read and not used (without it, assimp takes the first coordinate for it)
  if (vertices == 0.0) bad("0 vertices: the file has no vertices");
  if (faces == 0.0) bad("0 faces: the file has no faces");
  // The body starts at the next word (it may share the counts' line), as
  // assimp's reader goes on after the edge count.
  while (pos < head.size() && (space(pos) || head[pos] == '#')) {
    if (head[pos] == '#')
      while (pos < head.size() && head[pos] != '\n') ++pos;
    else if (head[pos++] == '\n')
      ++line;
  }
  in.clear();
  in.seekg(static_cast<std::streamoff>(pos));
  const size_t values = static_cast<size_t>(dimensions) + (homogeneous ? 1 : 0) + (normals ? 3 : 0) +
                        (colours ? 4 : 0) + (st ? 2 : 0);
  int ln = line - 1;
  std::string text;
  std::vector<std::string_view> tokens;
  double vertex = 0.0, face = 0.0;
  while (vertex < vertices || face < faces) {
    if (!next_line(in, &text, &ln))
      throw InputError(path + ": the OFF header declares " + plural(vertices, "vertex line") + " and " +
                       plural(faces, "face line") + ", the file ends after " + format_number(vertex) + " and " +
                       format_number(face) + " (truncated, or a wrong count)");
    if (text.empty()) continue;  // assimp skips empty lines, not those of spaces
    auto at = [&](const std::string& what) {
      throw InputError(path + ": line " + std::to_string(ln) + ": " + what);
    };
    if (const std::string c = control_character(text); !c.empty()) at(c);
    if (text.size() > 4095) at("longer than 4095 characters, which assimp's OFF reader splits into two lines");
    split(text, &tokens);
    if (!tokens.empty() && tokens[0][0] == '#')
      at(std::string("a comment among the ") + (vertex < vertices ? "vertices" : "faces") +
         " (assimp's OFF reader takes comments in the header only)");
    if (tokens.empty()) at("a line of spaces among the " + std::string(vertex < vertices ? "vertices" : "faces"));
    if (vertex < vertices) {
      if (tokens.size() != values)
        at("vertex " + format_number(vertex) + " has " + plural(static_cast<double>(tokens.size()), "value") +
           ", the OFF header (" + keyword + ") gives a vertex " + std::to_string(values) +
           (tokens.size() > values ? ": '" + shown(tokens[values]) + "' and on would be dropped" : ""));
      for (const std::string_view t : tokens) {
        double meant = 0.0;
        if (const std::string why = assimp_number<ai_real>(t, &meant); !why.empty())
          at("vertex value '" + shown(t) + "' " + why);
      }
      ++vertex;
      continue;
    }
    long long n = 0;
    if (const std::string why = read_whole(tokens[0], false, &n); !why.empty())
      at("a face's vertex count '" + shown(tokens[0]) + "' " + why);
    if (n > 9)
      throw InputError(path + ": OFF: line " + std::to_string(ln) + ": a face of " + std::to_string(n) +
                       " vertices; assimp's OFF reader drops a face of more than 9 (write the mesh as OBJ or PLY: "
                       "they take faces of any size)");
    if (n < 3)
      at("a face of " + plural(static_cast<double>(n), "vertex", "vertices") + "; radmesh needs polygons of 3 or more vertices");
    if (tokens.size() < static_cast<size_t>(n) + 1)
      at("a face of " + std::to_string(n) + " vertices lists " + std::to_string(tokens.size() - 1));
    for (size_t i = 1; i <= static_cast<size_t>(n); ++i) {
      long long v = 0;
      if (const std::string why = read_whole(tokens[i], false, &v); !why.empty())
        at("vertex index '" + shown(tokens[i]) + "' " + why);
      if (static_cast<double>(v) >= vertices)
        throw InputError(path + ": OFF: line " + std::to_string(ln) + ": Vertex index " + std::to_string(v) +
                         " is out of range: the file has " + plural(vertices, "vertex", "vertices"));
    }
    if (tokens.size() > static_cast<size_t>(n) + 5)
      at("'" + shown(tokens[static_cast<size_t>(n) + 5]) + "' after a face's indices and 4 colour values");
    for (size_t i = static_cast<size_t>(n) + 1; i < tokens.size(); ++i) {
      double c = 0.0;
      if (const std::string why = read_number(tokens[i], &c); !why.empty())
        at("'" + shown(tokens[i]) + "' after a face's indices (only colour values may follow them) " + why);
    }
    ++face;
  }
  while (next_line(in, &text, &ln)) {
    const size_t b = text.find_first_not_of(" \t");
    if (b != std::string::npos && text[b] != '#')
      throw InputError(path + ": line " + std::to_string(ln) + " holds data after the " + plural(faces, "face") +
                       " its OFF header declares (a wrong count would drop them)");
  }
}

// A binary STL must be as long as its facet count says. An ASCII STL (a
// file starting with "solid" that is not a binary STL of its size) is read
// line by line: solid NAME, then facets of "facet normal a b c", "outer
// loop", three "vertex x y z", "endloop", "endfacet", then "endsolid";
// further solids may follow. assimp skips a word it does not know, drops a
// value past the three of a vertex, and reads a truncated file up to its
// last whole facet, each without a word; radmesh refuses them, naming the
// line.
void check_stl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  char header[84] = {};
  in.read(header, sizeof header);
  const auto got = static_cast<size_t>(in.gcount());
  uint32_t count = 0;
  if (got == sizeof header) std::memcpy(&count, header + 80, 4);
  if (!ec && got == sizeof header && size == 84 + 50 * static_cast<uintmax_t>(count)) return;  // binary
  if (std::string(header, std::min<size_t>(got, 5)) != "solid") {
    if (ec || got < sizeof header)
      throw InputError(path + ": " + std::to_string(got) + " bytes: too short for a binary STL (84-byte header)");
    throw InputError(path + ": a binary STL stating " + std::to_string(count) + " facets needs " +
                     std::to_string(84 + 50 * static_cast<uintmax_t>(count)) + " bytes, the file has " +
                     std::to_string(size) + " (truncated, or not an STL file)");
  }
  in.clear();
  in.seekg(0);
  enum class State { outside, solid, facet, loop, looped } state = State::outside;
  std::string line;
  std::vector<std::string_view> tokens;
  int ln = 0, facet_at = 0, solid_at = 0, vertices = 0;
  double offset = 0.0;  // of the line read
  for (std::string raw; std::getline(in, raw);) {  // no stream per line: a million facets are 7 M lines
    ++ln;
    const double line_offset = offset;
    offset += static_cast<double>(raw.size()) + 1.0;
    if (!raw.empty() && raw.back() == '\r') raw.pop_back();
    auto bad = [&](const std::string& what) {
      throw InputError(path + ": line " + std::to_string(ln) + ": " + what);
    };
    if (const std::string c = control_character(raw); !c.empty()) bad(c);
    split(raw, &tokens);
    if (tokens.empty()) continue;
    const std::string_view head = tokens[0];
    auto expect_words = [&](size_t n, const char* form) {
      if (tokens.size() != n) bad("expected '" + std::string(form) + "', got '" + shown(raw) + "'");
    };
    auto expect_numbers = [&](size_t from, bool position) {
      for (size_t i = from; i < tokens.size(); ++i) {
        double meant = 0.0;
        const std::string why = position ? assimp_number<ai_real>(tokens[i], &meant) : read_number(tokens[i], &meant);
        if (!why.empty()) bad("value '" + shown(tokens[i]) + "' " + why);
      }
    };
    if (state != State::outside && state != State::solid && head == "facet")
      bad("'facet' before the facet of line " + std::to_string(facet_at) + " has its 'endfacet'");
    if (head == "solid") {
      if (state != State::outside)
        bad("'solid' inside the solid of line " + std::to_string(solid_at) + " (no 'endsolid' before it)");
      // assimp reads what follows an endsolid as another solid unless it
      // takes it for a binary STL of its length.
      const double rest = static_cast<double>(size) - line_offset - static_cast<double>(head.data() - raw.data());
      if (solid_at > 0 && rest >= 84) {
        const std::string c = bytes_at(path, static_cast<double>(size) - rest + 80, 4);
        uint32_t n = 0;
        std::memcpy(&n, c.data(), std::min<size_t>(4, c.size()));
        if (84.0 + 50.0 * n == rest) bad("assimp would read the file from this 'solid' on as a binary STL");
      }
      state = State::solid;
      solid_at = ln;
    } else if (head == "facet") {
      if (state != State::solid) bad("'facet' outside a solid");
      if (tokens.size() != 5 || tokens[1] != "normal") bad("expected 'facet normal a b c', got '" + shown(raw) + "'");
      expect_numbers(2, false);
      state = State::facet;
      facet_at = ln;
      vertices = 0;
    } else if (head == "outer") {
      if (state != State::facet) bad("'outer loop' outside a facet, or twice in one");
      expect_words(2, "outer loop");
      if (tokens[1] != "loop") bad("expected 'outer loop', got '" + shown(raw) + "'");
      state = State::loop;
    } else if (head == "vertex") {
      if (state != State::loop) bad("'vertex' outside a facet's outer loop");
      if (vertices == 3) bad("a fourth vertex in the facet of line " + std::to_string(facet_at) + "; a facet has 3");
      if (tokens.size() > 4) bad("'" + shown(tokens[4]) + "' after a vertex's 3 coordinates");
      if (tokens.size() < 4) bad("a vertex of " + plural(static_cast<double>(tokens.size() - 1), "coordinate"));
      expect_numbers(1, true);
      ++vertices;
    } else if (head == "endloop") {
      if (state != State::loop) bad("'endloop' outside a facet's outer loop");
      expect_words(1, "endloop");
      if (vertices != 3) bad("'endloop' after " + plural(vertices, "vertex", "vertices") + "; a facet has 3 vertices");
      state = State::looped;
    } else if (head == "endfacet") {
      if (state != State::looped) bad("'endfacet' before the facet's 'endloop'");
      expect_words(1, "endfacet");
      state = State::solid;
      facet_at = 0;
    } else if (head == "endsolid") {
      if (state != State::solid) bad("'endsolid' before the facet of line " + std::to_string(facet_at) +
                                     " has its 'endfacet'");
      state = State::outside;
    } else if (state == State::outside) {
      bad("'" + shown(head) + "' after 'endsolid' (assimp would drop it)");
    } else {
      bad("unknown word '" + shown(head) + "' (assimp would skip it)");
    }
  }
  if (state == State::facet || state == State::loop || state == State::looped)
    throw InputError(path + ": the facet of line " + std::to_string(facet_at) +
                     " has no 'endfacet' (truncated file)");
  if (state == State::solid) throw InputError(path + ": no 'endsolid' at the end (truncated file)");
}

}  // namespace radmesh::internal
