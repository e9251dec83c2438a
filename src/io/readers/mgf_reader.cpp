// MGF 2.0 scenes (Greg Ward's Materials and Geometry Format), read as
// mgf2rad and RenderPark read them: faces (f, fh; holes by seams),
// vertices, objects, includes, transforms with arrays, materials and
// colours, and the curved primitives cut into planar faces (mgf_shapes.cpp).
// docs/scenes.md ("MGF") lists what is read, warned about and refused.
// Numbers are read in radmesh's one syntax (text_syntax.h); every error
// names the file, the line, the entity and the value.

#include "io/readers/mgf.h"
#include "io/readers/scene_sources.h"
#include "core/degrees.h"
#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string_view>
#include <unordered_map>

namespace radmesh::internal {

namespace {

namespace fs = std::filesystem;
using mgf::Chromaticity;

// ---------------------------------------------------------------- files

// A file's statements: its text, each continued line joined to the next
// (the backslash and the newline made spaces), and where each statement
// that is not blank or a comment lies in it.
struct Statement {
  size_t begin = 0, end = 0;
  int line = 0;  // the line it starts on
};
struct File {
  std::string path;
  std::string text;
  std::vector<Statement> statements;
};

std::shared_ptr<const File> load_file(const std::string& path) {
  auto f = std::make_shared<File>();
  f->path = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open for reading");
  std::error_code ec;
  f->text.resize(static_cast<size_t>(fs::file_size(path, ec)));
  in.read(f->text.data(), static_cast<std::streamsize>(f->text.size()));
  f->text.resize(static_cast<size_t>(in.gcount()));
  if (in.bad()) throw IoError(path + ": read error");
  strip_byte_order_mark(f->text);
  std::string& t = f->text;
  auto add = [&](size_t begin, size_t end, int line) {
    const size_t first = t.find_first_not_of(" \t\r\v\f", begin);
    if (first < end && t[first] != '#') f->statements.push_back({begin, end, line});
  };
  size_t pos = 0, begin = 0;
  int line = 1, first_line = 1;
  bool open = false;  // the statement goes on in this line
  for (;; ++line) {
    const size_t nl = t.find('\n', pos);
    const size_t end = nl == std::string::npos ? t.size() : nl;
    size_t last = end;
    if (last > pos && t[last - 1] == '\r') t[--last] = ' ';
    if (!open) {
      begin = pos;
      first_line = line;
    }
    open = last > pos && t[last - 1] == '\\';
    if (open) {
      t[last - 1] = ' ';
      if (nl != std::string::npos) t[nl] = ' ';
    } else {
      add(begin, end, first_line);
    }
    if (nl == std::string::npos) break;
    pos = nl + 1;
  }
  if (open) add(begin, t.size(), first_line);
  return f;
}

// ---------------------------------------------------------------- transforms

// A similarity transform p -> a p + t.
struct Xf {
  glm::dmat3 a{1.0};
  Vec3 t{0.0};
  Vec3 apply(const Vec3& p) const { return a * p + t; }
  Xf then(const Xf& next) const { return {next.a * a, next.a * t + next.t}; }
  bool mirrors() const { return glm::determinant(a) < 0.0; }
  bool finite() const {
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(a[c].x) || !std::isfinite(a[c].y) || !std::isfinite(a[c].z) || !std::isfinite(t[c]))
        return false;
    return true;
  }
};

// `step` applied n times (by squaring: -i 1000000000 costs 30 products).
Xf power(Xf step, long long n) {
  Xf out;
  for (; n > 0; n >>= 1, step = step.then(step))
    if (n & 1) out = out.then(step);
  return out;
}

// An xf's arguments: groups of steps, each applied a number of times (-i N)
// or as many times as its array's index (-a N: instance k applies it k times).
struct XfSpec {
  struct Group {
    Xf step;
    long long count = 1;
    int array = -1;  // index into sizes, for -a
  };
  std::vector<Group> groups;
  std::vector<long long> sizes;
};

// An open xf context: its arguments, the array instance it is at, and the
// transform in effect inside it.
struct XfContext {
  XfSpec spec;
  std::vector<long long> index;
  Xf total;
  size_t body = 0;  // the statement after it, where an array's next instance starts
  int line = 0;
};

// ---------------------------------------------------------------- contexts

struct Vertex {
  Vec3 p{0.0};
  Vec3 n{0.0};  // zero: none
};

struct Mtl {
  int sides = 2;
  double rd = 0.0, ed = 0.0;
  Chromaticity rd_color, ed_color;
  std::string file;  // where it was begun (m NAME =, or m)
  int line = 0, rd_line = 0, ed_line = 0;
  std::string rd_at, ed_at;  // "file:line" of its rd and ed (an include's, maybe)
  bool changed = false;  // set since MGF's default (a two-sided black absorber)
  int index = -1;        // in SceneSource::materials, while unchanged since
};

// Transparent lookup: names are looked up as string_views of the line.
struct NameHash {
  using is_transparent = void;
  size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
};
template <class T>
using Named = std::unordered_map<std::string, T, NameHash, std::equal_to<>>;

// How often a thing happened and where first: one warning each.
struct Tally {
  long long count = 0;
  std::string first;
  void add(const std::string& at) {
    if (count++ == 0) first = at;
  }
};

// ---------------------------------------------------------------- the reader

class Reader {
public:
  Reader(const SceneOptions& options, const MgfLimits& limits) : options_(options), limits_(limits) {}

  SceneSource read(const std::string& path) {
    unnamed_material_.file = path;
    check_input_file(path, "an MGF file");
    run_file(path, file_key(path), 0);
    finish();
    return std::move(out_);
  }

private:
  // ---- files

  // One name per file, however it is spelt (a.mgf, ./a.mgf, ../d/a.mgf).
  static std::string file_key(const std::string& path) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(path, ec);
    return ec ? fs::path(path).lexically_normal().string() : canonical.string();
  }

  void run_file(const std::string& path, const std::string& key, int depth) {
    std::shared_ptr<const File>& cached = files_[key];
    if (!cached) cached = load_file(path);
    const File& f = *cached;
    including_.push_back(key);
    const File* outer_file = file_;
    const Statement* outer_statement = statement_;
    const int outer_line = line_;
    file_ = &f;
    const size_t xf_base = xfs_.size(), o_base = objects_.size();
    for (size_t i = 0;;) {
      if (i < f.statements.size()) {
        i = execute(i, depth, xf_base, o_base);
        continue;
      }
      // Contexts left open at the end of their file end there (an array
      // makes its other instances first).
      if (xfs_.size() > xf_base) {
        count_statement();
        const size_t open = xfs_.size();
        const int line = xfs_.back().line;
        i = end_xf(i);
        if (xfs_.size() < open) open_at_end_.add(f.path + ":" + std::to_string(line) + " xf");
        continue;
      }
      if (objects_.size() > o_base) open_at_end_.add(f.path + ": o " + shown(objects_.back()));
      objects_.resize(o_base);
      break;
    }
    file_ = outer_file;
    statement_ = outer_statement;
    line_ = outer_line;
    including_.pop_back();
  }

  // ---- statements

  void count_statement() {
    if (++statements_ > limits_.statements)
      throw InputError(at() + "more than " + std::to_string(limits_.statements) +
                       " statements executed (each instance of an array and each include counted): radmesh reads "
                       "at most that many");
  }

  // Executes statement i; returns the index of the next one (an array's
  // end may go back to its first).
  size_t execute(size_t i, int depth, size_t xf_base, size_t o_base) {
    statement_ = &file_->statements[i];
    line_ = statement_->line;
    count_statement();
    tokenize(*statement_);
    if (tok_[0] != "xf") {
      entity(depth, o_base);
      return i + 1;
    }
    if (tok_.size() > 1) {
      begin_xf(1, i + 1);
      return i + 1;
    }
    if (xfs_.size() == xf_base) fail("no transform begun in this file to end");
    return end_xf(i + 1);
  }

  void entity(int depth, size_t o_base) {
    const std::string_view key = tok_[0];
    if (key == "v") {
      vertex_ = named_context(vertices_, unnamed_vertex_, Vertex{}, "vertex");
    } else if (key == "p" || key == "n") {
      expect(4, std::string(key) + " X Y Z");
      (key == "p" ? vertex_->p : vertex_->n) = Vec3(number(1), number(2), number(3));
    } else if (key == "f") {
      face();
    } else if (key == "fh") {
      face_with_holes();
    } else if (key == "o") {
      if (tok_.size() > 2) fail("expected 'o NAME' or 'o', got '" + text() + "'");
      if (tok_.size() == 2) {
        if (static_cast<int>(objects_.size()) >= limits_.object_depth)
          fail("objects nested more than " + std::to_string(limits_.object_depth) + " deep");
        objects_.emplace_back(tok_[1]);
      } else {
        if (objects_.size() == o_base) fail("no object begun in this file to end");
        objects_.pop_back();
      }
    } else if (key == "i") {
      include(depth);
    } else if (key == "c" || key == "cxy" || key == "cspec" || key == "cct" || key == "cmix") {
      color();
    } else if (key == "m" || key == "sides" || key == "rd" || key == "ed") {
      material();
    } else if (key == "td" || key == "rs" || key == "ts" || key == "ir") {
      unused_property();
    } else if (key == "ies") {
      if (tok_.size() < 2) fail("expected 'ies FILE [-m F] [transform]'");
      unused_["ies (an IES luminaire): not loaded"].add(at_line());
    } else if (key == "sph" || key == "cyl" || key == "cone" || key == "ring" || key == "torus" || key == "prism") {
      primitive();
    } else {
      unknown_.add(at_line() + " '" + shown(key) + "'");
    }
  }

  // Splits the statement at white space (as MGF's parser does); any other
  // control character is refused, not read as part of a name or number.
  void tokenize(const Statement& s) {
    tok_.clear();
    const std::string& t = file_->text;
    auto blank = [](unsigned char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
    for (size_t k = s.begin; k < s.end;) {
      if (blank(static_cast<unsigned char>(t[k]))) {
        ++k;
        continue;
      }
      const size_t start = k;
      for (; k < s.end && !blank(static_cast<unsigned char>(t[k])); ++k) {
        const auto d = static_cast<unsigned char>(t[k]);
        if (d < 0x20 || d == 0x7f) {
          char code[8];
          std::snprintf(code, sizeof code, "0x%02X", static_cast<unsigned>(d));
          throw InputError(at() + "control character " + code + " in the line (only spaces and tabs separate values)");
        }
      }
      tok_.emplace_back(t.data() + start, k - start);
    }
  }

  // ---- messages

  std::string at() const { return where(file_->path, line_); }
  std::string at_line() const { return file_->path + ":" + std::to_string(line_); }
  std::string text() const {
    std::string out;
    for (const std::string_view w : tok_) {
      if (!out.empty()) out += ' ';
      out += w;
    }
    return shown(out, 80);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(at() + std::string(tok_[0]) + ": " + what);
  }
  void expect(size_t n, const std::string& form) const {
    if (tok_.size() != n) fail("expected '" + form + "', got '" + text() + "'");
  }
  double number(size_t k) const {
    double v = 0.0;
    const std::string why = read_number(tok_[k], &v);
    if (!why.empty()) fail("'" + shown(tok_[k]) + "' " + why);
    return v;
  }
  long long whole(size_t k) const {
    long long v = 0;
    const std::string why = read_whole(tok_[k], false, &v);
    if (!why.empty()) fail("'" + shown(tok_[k]) + "' " + why);
    return v;
  }
  Vertex& vertex(size_t k) {
    const auto it = vertices_.find(tok_[k]);
    if (it == vertices_.end()) fail("unknown vertex '" + shown(tok_[k]) + "'");
    return it->second;
  }

  // ---- named contexts: v, c, m share the forms X, X NAME, X NAME =, X NAME = TEMPLATE

  // The context the statement names in `table` (the unnamed one, reset to
  // `fresh`, for the bare keyword); a copy of TEMPLATE or `fresh` for a new one.
  template <class T>
  T* named_context(Named<T>& table, T& unnamed, const T& fresh, const char* what) {
    if (tok_.size() == 1) {
      unnamed = fresh;
      return &unnamed;
    }
    if (tok_.size() == 2) {
      const auto it = table.find(tok_[1]);
      if (it == table.end()) fail("unknown " + std::string(what) + " '" + shown(tok_[1]) + "'");
      return &it->second;
    }
    if (tok_[2] != "=" || tok_.size() > 4)
      fail("expected '" + std::string(tok_[0]) + " [NAME [= [TEMPLATE]]]', got '" + text() + "'");
    T value = fresh;
    if (tok_.size() == 4) {
      const auto it = table.find(tok_[3]);
      if (it == table.end()) fail("unknown " + std::string(what) + " '" + shown(tok_[3]) + "' as a template");
      value = it->second;
    }
    T& slot = table[std::string(tok_[1])];
    slot = value;
    return &slot;
  }

  // ---- faces

  void face() {
    if (tok_.size() < 4) fail("a face needs at least 3 vertices, got '" + text() + "'");
    if (static_cast<long long>(tok_.size()) - 1 > limits_.face_vertices)
      fail("a face of " + std::to_string(tok_.size() - 1) + " vertices; radmesh reads faces of at most " +
           std::to_string(limits_.face_vertices));
    std::vector<Vec3> loop;
    for (size_t k = 1; k < tok_.size(); ++k) loop.push_back(vertex(k).p);
    mgf::Seamed parts;
    if (!mgf::split_at_seams(std::move(loop), &parts)) fail("the face's seams leave no loop of 3 or more vertices");
    emit(std::move(parts.outer), std::move(parts.holes));
    for (auto& island : parts.islands) emit(std::move(island), {});
  }

  void face_with_holes() {
    if (static_cast<long long>(tok_.size()) - 1 > limits_.face_vertices)
      fail("a face of " + std::to_string(tok_.size() - 1) + " vertices; radmesh reads faces of at most " +
           std::to_string(limits_.face_vertices));
    std::vector<std::vector<Vec3>> loops(1);
    for (size_t k = 1; k < tok_.size(); ++k) {
      if (tok_[k] == "-") {
        loops.emplace_back();
        continue;
      }
      loops.back().push_back(vertex(k).p);
    }
    for (size_t l = 0; l < loops.size(); ++l)
      if (loops[l].size() < 3)
        fail((l == 0 ? std::string("the outline") : "hole " + std::to_string(l)) + " has " +
             std::to_string(loops[l].size()) + " vertices; each contour needs at least 3 (contours are separated "
             "by '-')");
    std::vector<Vec3> outer = std::move(loops.front());
    loops.erase(loops.begin());
    emit(std::move(outer), std::move(loops));
  }

  // A face in the current object space: transformed, given the current
  // material, named, and counted.
  void emit(std::vector<Vec3> outer, std::vector<std::vector<Vec3>> holes) {
    if (static_cast<long long>(out_.faces.size()) >= limits_.faces)
      fail("more than " + std::to_string(limits_.faces) +
           " faces (arrays, includes and curved primitives counted): radmesh reads at most that many");
    points_ += static_cast<long long>(outer.size());
    for (const auto& h : holes) points_ += static_cast<long long>(h.size());
    if (points_ > limits_.points)
      fail("more than " + std::to_string(limits_.points) +
           " face vertices (arrays, includes and curved primitives counted): radmesh reads at most that many");
    const Xf& xf = xfs_.empty() ? identity_ : xfs_.back().total;
    RawFace f;
    f.points = std::move(outer);
    f.holes = std::move(holes);
    transform_face(f, [&](const Vec3& p) { return xf.apply(p); }, xf.mirrors());
    for (const std::string& o : objects_) {
      if (!f.name.empty()) f.name += '.';
      f.name += o;
    }
    if (f.name.empty()) f.name = fs::path(file_->path).stem().string();
    f.material = material_index();
    f.file = file_->path;
    f.line = line_;
    if (material_->sides == 2) two_sided_.add(at_line());
    if (material_ == &unnamed_material_ && !material_->changed) default_material_.add(at_line());
    out_.faces.push_back(std::move(f));
  }

  // ---- transforms

  void begin_xf(size_t from, size_t body) {
    XfContext c;
    c.spec = parse_xf(from);
    c.index.assign(c.spec.sizes.size(), 0);
    c.body = body;
    c.line = line_;
    xfs_.push_back(std::move(c));
    set_total(xfs_.back());
  }

  // Ends the innermost xf context, or starts its array's next instance:
  // returns the statement to go on from (`next` when it ended).
  size_t end_xf(size_t next) {
    XfContext& c = xfs_.back();
    for (size_t k = c.index.size(); k-- > 0;) {
      if (++c.index[k] < c.spec.sizes[k]) {
        set_total(c);
        return c.body;
      }
      c.index[k] = 0;
    }
    xfs_.pop_back();
    return next;
  }

  // The context's transform at its array instance, inside the enclosing
  // one's (whose arguments come after: MGF prepends a context's arguments).
  void set_total(XfContext& c) {
    Xf local;
    for (const XfSpec::Group& g : c.spec.groups)
      local = local.then(power(g.step, g.array >= 0 ? c.index[static_cast<size_t>(g.array)] : g.count));
    c.total = local.then(xfs_.size() > 1 ? xfs_[xfs_.size() - 2].total : identity_);
    if (!c.total.finite())
      throw InputError(where(file_->path, c.line) + "the transform overflows double precision" +
                       (c.index.empty() ? std::string() : " (in an array instance)"));
  }

  XfSpec parse_xf(size_t k) {
    XfSpec spec;
    XfSpec::Group g;
    auto args = [&](size_t n) {
      if (k + n >= tok_.size()) fail("'" + std::string(tok_[k]) + "' needs " + std::to_string(n) + " value(s)");
    };
    for (; k < tok_.size(); ++k) {
      const std::string_view a = tok_[k];
      Xf s;
      if (a == "-t") {
        args(3);
        s.t = Vec3(number(k + 1), number(k + 2), number(k + 3));
        k += 3;
      } else if (a == "-rx" || a == "-ry" || a == "-rz") {
        args(1);
        double c = 1.0, sn = 0.0;
        cos_sin_degrees(number(++k), &c, &sn);
        const int axis = a[2] - 'x', u = (axis + 1) % 3, v = (axis + 2) % 3;
        s.a[u][u] = c;  // counter-clockwise looking down the axis
        s.a[u][v] = sn;
        s.a[v][u] = -sn;
        s.a[v][v] = c;
      } else if (a == "-s") {
        args(1);
        const double f = number(++k);
        if (f == 0.0) fail("-s 0 would flatten the geometry; the scale factor must not be 0");
        s.a = glm::dmat3(f);
      } else if (a == "-mx" || a == "-my" || a == "-mz") {
        s.a[a[2] - 'x'][a[2] - 'x'] = -1.0;
      } else if (a == "-i" || a == "-a") {
        args(1);
        const long long n = whole(++k);
        if (a == "-a" && n < 1) fail("-a 0: an array needs at least 1 instance");
        spec.groups.push_back(g);
        g = XfSpec::Group();
        if (a == "-i") {
          g.count = n;
        } else {
          g.array = static_cast<int>(spec.sizes.size());
          spec.sizes.push_back(n);
        }
        continue;
      } else {
        fail("unknown transform argument '" + shown(a) + "' (MGF takes -t, -rx, -ry, -rz, -s, -mx, -my, -mz, -i, -a)");
      }
      g.step = g.step.then(s);
    }
    spec.groups.push_back(g);
    return spec;
  }

  void include(int depth) {
    if (tok_.size() < 2) fail("expected 'i FILE [transform]'");
    const std::string name(tok_[1]);
    const fs::path given(name);
    const std::string path = (given.is_absolute() ? given : fs::path(file_->path).parent_path() / given).string();
    std::error_code ec;
    if (!fs::exists(path, ec)) fail("'" + shown(name) + "' not found (looked for " + shown(path, 200) + ")");
    if (depth + 1 > limits_.include_depth)
      fail("'" + shown(name) + "': includes nested more than " + std::to_string(limits_.include_depth) + " deep");
    const std::string key = file_key(path);
    if (std::find(including_.begin(), including_.end(), key) != including_.end()) {
      std::string chain;
      for (const std::string& f : including_) chain += fs::path(f).filename().string() + " -> ";
      fail("'" + shown(name) + "' includes itself: " + chain + fs::path(key).filename().string());
    }
    try {
      check_input_file(path, "an MGF file");
    } catch (const IoError& e) {
      fail(e.what());
    }
    if (tok_.size() == 2) return run_file(path, key, depth + 1);
    // As if enclosed in xf ARGS ... xf, every array instance in turn.
    begin_xf(2, 0);
    do {
      count_statement();
      run_file(path, key, depth + 1);
      tokenize(*statement_);
    } while (end_xf(1) == 0);
  }

  // ---- colours and materials

  void color() {
    const std::string_view key = tok_[0];
    if (key == "c") {
      color_ = named_context(colors_, unnamed_color_, Chromaticity{}, "colour");
    } else if (key == "cxy") {
      expect(3, "cxy X Y");
      const double x = number(1), y = number(2);
      if (x < 0.0 || y <= 0.0 || x + y > 1.0)
        fail(format_number(x) + " " + format_number(y) + " is not a chromaticity (x >= 0, y > 0, x + y <= 1)");
      *color_ = {x, y};
    } else if (key == "cspec") {
      if (tok_.size() < 5) fail("expected 'cspec MIN_NM MAX_NM V1 V2 ...' (at least 2 values), got '" + text() + "'");
      const double lo = number(1), hi = number(2);
      if (!(lo > 0.0 && hi > lo)) fail("the wavelengths " + format_number(lo) + " to " + format_number(hi) + " nm are not a range");
      std::vector<double> values;
      for (size_t k = 3; k < tok_.size(); ++k) {
        values.push_back(number(k));
        if (values.back() < 0.0) fail("value " + format_number(values.back()) + " is negative");
      }
      if (const std::string why = mgf::spectrum_chromaticity(lo, hi, values, color_); !why.empty())
        fail("the spectrum " + why);
    } else if (key == "cct") {
      expect(2, "cct KELVIN");
      const double kelvin = number(1);
      if (!(kelvin > 0.0)) fail(format_number(kelvin) + " K is not a temperature above 0");
      if (const std::string why = mgf::black_body_chromaticity(kelvin, color_); !why.empty())
        fail(format_number(kelvin) + " K " + why);
    } else {  // cmix
      if (tok_.size() < 3 || tok_.size() % 2 == 0) fail("expected 'cmix W1 C1 W2 C2 ...', got '" + text() + "'");
      std::vector<Chromaticity> colors;
      std::vector<double> weights;
      double sum = 0.0;
      for (size_t k = 1; k < tok_.size(); k += 2) {
        weights.push_back(number(k));
        if (weights.back() < 0.0) fail("weight " + format_number(weights.back()) + " is negative");
        sum += weights.back();
        const auto it = colors_.find(tok_[k + 1]);
        if (it == colors_.end()) fail("unknown colour '" + shown(tok_[k + 1]) + "'");
        colors.push_back(it->second);
      }
      if (!(sum > 0.0) || !std::isfinite(sum)) fail("the weights add up to " + format_number(sum) + ", not a positive number");
      *color_ = mgf::mix(colors, weights);
    }
  }

  void material() {
    const std::string_view key = tok_[0];
    if (key == "m") {
      Mtl fresh;
      fresh.file = file_->path;
      fresh.line = line_;
      Mtl* m = named_context(materials_, unnamed_material_, fresh, "material");
      if (tok_.size() > 2) {  // a new context, or a copy of a template under a new name
        m->file = file_->path;
        m->line = line_;
        m->index = -1;
      }
      material_ = m;
      material_name_ = tok_.size() >= 2 ? std::string(tok_[1]) : std::string();
      return;
    }
    material_->changed = true;
    material_->index = -1;
    if (key == "sides") {
      expect(2, "sides 1|2");
      const long long n = whole(1);
      if (n != 1 && n != 2) fail("'" + std::string(tok_[1]) + "': a material has 1 or 2 sides");
      material_->sides = static_cast<int>(n);
    } else {
      expect(2, std::string(key) + " VALUE");
      const double v = number(1);
      if (key == "rd") {
        if (v < 0.0 || v > 1.0) fail(format_number(v) + " is outside [0, 1]");
        material_->rd = v;
        material_->rd_color = *color_;
        material_->rd_line = line_;
        material_->rd_at = at_line();
      } else {
        if (v < 0.0) fail(format_number(v) + " is negative");
        material_->ed = v;
        material_->ed_color = *color_;
        material_->ed_line = line_;
        material_->ed_at = at_line();
      }
    }
  }

  // td, rs, ts, ir: read (their values checked), not used by a diffuse method.
  void unused_property() {
    const std::string_view key = tok_[0];
    const bool two = key != "td";
    expect(two ? 3 : 2, std::string(key) + (two ? " VALUE VALUE" : " VALUE"));
    for (size_t k = 1; k < tok_.size(); ++k) number(k);
    static const std::map<std::string_view, const char*> what = {
        {"td", "td (diffuse transmittance)"}, {"rs", "rs (specular reflectance)"},
        {"ts", "ts (specular transmittance)"}, {"ir", "ir (index of refraction)"}};
    unused_[std::string(what.at(key)) + ": read, not used (radmesh's methods are diffuse and opaque)"].add(at_line());
  }

  // The current material in out_.materials: its RGB now, merged with an
  // earlier one of the same name and values; a name whose values changed
  // gets a number ("red (2)").
  int material_index() {
    Mtl& m = *material_;
    if (m.index >= 0) return m.index;
    std::string name = material_ == &unnamed_material_ ? (m.changed ? "(unnamed)" : "(default)") : material_name_;
    Material mat;
    mat.file = m.file;
    mat.line = m.line;
    mat.reflectance_line = m.rd_line;
    mat.emission_line = m.ed_line;
    bool clipped_rd = false, clipped_ed = false;
    mat.reflectance = mgf::to_rgb(m.rd_color, m.rd, &clipped_rd);
    mat.emission = mgf::to_rgb(m.ed_color, m.ed / mgf::kWhiteEfficacy, &clipped_ed);
    if (clipped_rd) clipped_.add(m.rd_at + " rd");
    if (clipped_ed) clipped_.add(m.ed_at + " ed");
    if (max3(mat.reflectance) >= 1.0)
      throw InputError(m.rd_at + ": rd " + format_number(m.rd) + " with the colour x " +
                       format_number(m.rd_color.x) + " y " + format_number(m.rd_color.y) + " is the RGB reflectance " +
                       format_number(mat.reflectance.x) + " " + format_number(mat.reflectance.y) + " " +
                       format_number(mat.reflectance.z) +
                       ": a channel of 1 or more (radmesh needs each below 1); lower rd or the colour's saturation");
    std::vector<int>& versions = versions_[name];
    for (const int k : versions) {
      const Material& old = out_.materials[static_cast<size_t>(k)];
      if (old.reflectance == mat.reflectance && old.emission == mat.emission) return m.index = k;
    }
    mat.name = versions.empty() ? name : name + " (" + std::to_string(versions.size() + 1) + ")";
    if (max3(mat.emission) > 0.0) emits_ = true;
    versions.push_back(static_cast<int>(out_.materials.size()));
    out_.materials.push_back(std::move(mat));
    return m.index = versions.back();
  }

  // ---- curved primitives and prisms

  void primitive() {
    const std::string_view key = tok_[0];
    const double tolerance = options_.curve_tolerance;
    const mgf::FaceSink sink = [&](mgf::ShapeFace&& f) { emit(std::move(f.outer), std::move(f.holes)); };
    const size_t before = out_.faces.size();
    if (key == "prism") {
      if (tok_.size() < 5) fail("expected 'prism V1 V2 V3 ... LENGTH', got '" + text() + "'");
      std::vector<Vec3> base;
      for (size_t k = 1; k + 1 < tok_.size(); ++k) base.push_back(vertex(k).p);
      const double length = number(tok_.size() - 1);
      if (length == 0.0) fail("a length of 0 makes no solid");
      if (!(glm::length(newell_normal(base)) > 0.0)) fail("its end face has no area");
      mgf::prism(base, length, sink);
      return;
    }
    auto normal_of = [&](const Vertex& v) {
      if (!(glm::length(v.n) > 0.0)) fail("vertex '" + shown(tok_[1]) + "' has no normal (n), which gives its plane");
      return glm::normalize(v.n);
    };
    if (key == "sph") {
      expect(3, "sph CENTER RADIUS");
      const Vec3 c = vertex(1).p;
      const double r = number(2);
      if (r == 0.0) fail("a radius of 0 makes no sphere");
      mgf::sphere(c, r, tolerance, sink);
    } else if (key == "cyl" || key == "cone") {
      const bool cyl = key == "cyl";
      expect(cyl ? 4 : 5, cyl ? "cyl V1 RADIUS V2" : "cone V1 RADIUS1 V2 RADIUS2");
      const Vec3 a = vertex(1).p, b = vertex(3).p;
      const double ra = number(2), rb = cyl ? ra : number(4);
      if (ra == 0.0 && rb == 0.0) fail("both radii are 0");
      if (ra * rb < 0.0) fail("the radii " + format_number(ra) + " and " + format_number(rb) + " differ in sign");
      if (a == b) fail("its two ends are at one point (a ring is the flat case)");
      mgf::cone(a, ra, b, rb, tolerance, sink);
    } else {  // ring, torus
      expect(4, std::string(key) + " CENTER RMIN RMAX");
      const Vertex& v = vertex(1);
      const Vec3 n = normal_of(v);
      const double rmin = number(2), rmax = number(3);
      if (key == "ring") {
        if (rmin < 0.0 || rmax <= rmin) fail("needs 0 <= rmin < rmax, got " + format_number(rmin) + " " + format_number(rmax));
        mgf::ring(v.p, n, rmin, rmax, tolerance, sink);
      } else {
        if (rmin * rmax < 0.0 || std::abs(rmax) <= std::abs(rmin))
          fail("needs radii of one sign with |rmin| < |rmax|, got " + format_number(rmin) + " " + format_number(rmax));
        mgf::torus(v.p, n, rmin, rmax, tolerance, sink);
      }
    }
    ++curved_;
    curved_faces_ += static_cast<long long>(out_.faces.size() - before);
  }

  // ---- the report

  void finish() {
    auto say = [&](const Tally& t, const std::string& what, std::vector<std::string>& to) {
      if (t.count > 0) to.push_back(what + " (" + std::to_string(t.count) + ", first at " + t.first + ")");
    };
    std::vector<std::string>& materials = out_.warnings;
    std::vector<std::string>& geometry = out_.geometry_warnings;
    for (const auto& [what, t] : unused_) say(t, what, materials);
    say(unknown_, "unknown MGF entities, ignored as the format asks", geometry);
    say(open_at_end_, "contexts left open at the end of their file, ended there", geometry);
    say(default_material_, "faces without a material: MGF's default, a two-sided black absorber (reflectance 0)",
        materials);
    say(two_sided_, "faces of two-sided materials (MGF's default, sides 2): radmesh lights each face on its front only, "
                    "the side its vertices run counter-clockwise around", materials);
    say(clipped_, "colours outside the gamut of Radiance's RGB primaries: negative components set to 0", materials);
    if (curved_ > 0)
      geometry.push_back("MGF curved primitives: " + std::to_string(curved_) + " cut into " +
                              std::to_string(curved_faces_) + " planar faces within curve_tolerance " +
                              format_number(options_.curve_tolerance) + " of their radius");
    if (emits_)
      out_.warnings.push_back("MGF emission (ed, lux) converted to radiant exitance at 179 lm/W, Radiance's white "
                              "efficacy (ed 179 emits 1 W/m^2)");
  }

  const SceneOptions& options_;
  const MgfLimits& limits_;
  SceneSource out_;
  std::map<std::string, std::shared_ptr<const File>> files_;  // by canonical path, read once
  std::vector<std::string> including_;                         // the include chain, for cycles
  const File* file_ = nullptr;
  const Statement* statement_ = nullptr;
  int line_ = 0;
  long long statements_ = 0;
  long long points_ = 0;
  std::vector<std::string_view> tok_;

  Named<Vertex> vertices_;
  Vertex unnamed_vertex_;
  Vertex* vertex_ = &unnamed_vertex_;
  Named<Chromaticity> colors_;
  Chromaticity unnamed_color_;
  Chromaticity* color_ = &unnamed_color_;
  Named<Mtl> materials_;
  Mtl unnamed_material_;
  Mtl* material_ = &unnamed_material_;
  std::string material_name_;
  std::map<std::string, std::vector<int>> versions_;  // material name -> its indices in out_.materials
  std::vector<std::string> objects_;
  std::vector<XfContext> xfs_;
  const Xf identity_;

  std::map<std::string, Tally> unused_;
  Tally unknown_, open_at_end_, default_material_, two_sided_, clipped_;
  long long curved_ = 0, curved_faces_ = 0;
  bool emits_ = false;
};

}  // namespace

SceneSource read_mgf_source(const std::string& path, const SceneOptions& options, const MgfLimits& limits) {
  scene_option_table().check(options);
  return Reader(options, limits).read(path);
}

}  // namespace radmesh::internal
