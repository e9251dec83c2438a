// numpy arrays for the Python module: views of the library's vectors
// without copying (each holds its owner alive), and the checks of arrays
// a user passes in, errors naming the argument.
#pragma once

#include "radmesh/errors.h"
#include "radmesh/geometry.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace radmesh::python {

namespace py = pybind11;

// A read-only view of `count` x `columns` values of T at `data`, owned by
// `owner` (the array keeps it alive).
template <class T>
py::array view_of(const T* data, size_t count, size_t columns, std::shared_ptr<const void> owner) {
  auto* keep = new std::shared_ptr<const void>(std::move(owner));
  py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<const void>*>(p); });
  std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(count)};
  std::vector<py::ssize_t> strides = {static_cast<py::ssize_t>(columns * sizeof(T))};
  if (columns > 1) {
    shape.push_back(static_cast<py::ssize_t>(columns));
    strides.push_back(static_cast<py::ssize_t>(sizeof(T)));
  }
  py::array a(py::dtype::of<T>(), shape, strides, data, base);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

template <class T>
py::array view(const std::vector<T>& v, std::shared_ptr<const void> owner) {
  return view_of(v.data(), v.size(), 1, std::move(owner));
}

inline py::array view_bool(const std::vector<char>& v, std::shared_ptr<const void> owner) {
  return view_of(reinterpret_cast<const bool*>(v.data()), v.size(), 1, std::move(owner));
}

// Rows of three: points and colours (glm's dvec3 is three doubles), triangles.
inline py::array view_rows(const std::vector<Vec3>& v, std::shared_ptr<const void> owner) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  return view_of(reinterpret_cast<const double*>(v.data()), v.size(), 3, std::move(owner));
}
inline py::array view_rows(const std::vector<std::array<int, 3>>& v, std::shared_ptr<const void> owner) {
  static_assert(sizeof(std::array<int, 3>) == 3 * sizeof(int));
  return view_of(reinterpret_cast<const int*>(v.data()), v.size(), 3, std::move(owner));
}

// ---- arrays given -----------------------------------------------------------

// An argument as a numpy array of numbers (real or integer kinds); InputError
// naming it otherwise.
inline py::array numeric_array(const py::object& value, const std::string& name) {
  py::array a;
  try {
    a = py::array::ensure(value);
  } catch (...) {
  }
  if (!a) throw InputError(name + ": not an array");
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw InputError(name + ": an array of numbers wanted, got dtype " + py::str(a.dtype()).cast<std::string>());
  return a;
}

// The array as contiguous doubles (a copy where it is not); InputError when
// numpy cannot make one (a broadcast view far larger than memory).
inline py::array_t<double, py::array::c_style> as_doubles(const py::array& a, const std::string& name) {
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!d) {
    PyErr_Clear();
    throw InputError(name + ": cannot be read as " + std::to_string(a.size()) + " numbers (not enough memory for them)");
  }
  return d;
}

struct Matrix {
  std::vector<double> values;
  size_t rows = 0, columns = 0;
  Vec3 row(long long r) const {
    const double* p = &values[static_cast<size_t>(r) * columns];
    return {p[0], p[1], p[2]};
  }
};

// An (n, columns) array of finite reals.
inline Matrix real_matrix(const py::object& value, const std::string& name, size_t columns) {
  const py::array a = numeric_array(value, name);
  if (a.ndim() != 2 || static_cast<size_t>(a.shape(1)) != columns)
    throw InputError(name + ": shape (n, " + std::to_string(columns) + ") wanted, got " +
                     py::str(py::tuple(a.attr("shape"))).cast<std::string>());
  const auto d = as_doubles(a, name);
  Matrix m;
  m.rows = static_cast<size_t>(a.shape(0));
  m.columns = columns;
  m.values.assign(d.data(), d.data() + m.rows * columns);
  for (size_t k = 0; k < m.values.size(); ++k)
    if (!std::isfinite(m.values[k]))
      throw InputError(name + "[" + std::to_string(k / columns) + ", " + std::to_string(k % columns) +
                       "]: " + format_number(m.values[k]) + " is not a finite number");
  return m;
}

// A one-dimensional array of integers (an integer dtype, or reals that are
// whole numbers).
inline std::vector<long long> integer_vector(const py::object& value, const std::string& name) {
  const py::array a = numeric_array(value, name);
  if (a.ndim() != 1)
    throw InputError(name + ": a one-dimensional array wanted, got " + std::to_string(a.ndim()) + " dimensions");
  const auto d = as_doubles(a, name);
  std::vector<long long> out(static_cast<size_t>(a.shape(0)));
  for (size_t k = 0; k < out.size(); ++k) {
    const double x = d.data()[k];
    if (!(std::abs(x) < 9e15) || x != std::floor(x))
      throw InputError(name + "[" + std::to_string(k) + "]: " + format_number(x) + " is not an integer");
    out[k] = static_cast<long long>(x);
  }
  return out;
}

// Polygons of any size as (offsets, indices): face f has the vertices
// indices[offsets[f]:offsets[f + 1]]; or an (F, k) array of k-gons.
struct Polygons {
  std::vector<long long> offsets, indices;
  size_t count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
};

inline Polygons polygons(const py::object& value, const std::string& name, long long vertex_count) {
  Polygons p;
  if (py::isinstance<py::tuple>(value) || py::isinstance<py::list>(value)) {
    const py::sequence s = value.cast<py::sequence>();
    if (s.size() != 2) throw InputError(name + ": (offsets, indices) or an (F, k) array wanted");
    p.offsets = integer_vector(s[0], name + " offsets");
    p.indices = integer_vector(s[1], name + " indices");
  } else {
    const py::array a = numeric_array(value, name);
    if (a.ndim() != 2) throw InputError(name + ": (offsets, indices) or an (F, k) array wanted");
    const long long k = a.shape(1);
    if (k < 3 && a.shape(0) > 0)
      throw InputError(name + ": faces of " + std::to_string(k) + " vertices; a face needs at least 3");
    const py::object flat = a.attr("reshape")(-1);
    p.indices = integer_vector(flat, name);
    for (long long f = 0; f <= a.shape(0); ++f) p.offsets.push_back(f * k);
  }
  if (p.offsets.empty() || p.offsets.front() != 0)
    throw InputError(name + " offsets: must start with 0 (one more entry than faces)");
  if (p.offsets.back() != static_cast<long long>(p.indices.size()))
    throw InputError(name + " offsets: the last is " + std::to_string(p.offsets.back()) + ", not the " +
                     std::to_string(p.indices.size()) + " indices given");
  for (size_t f = 0; f + 1 < p.offsets.size(); ++f)
    if (p.offsets[f + 1] - p.offsets[f] < 3)
      throw InputError(name + "[" + std::to_string(f) + "]: " + std::to_string(p.offsets[f + 1] - p.offsets[f]) +
                       " vertices; a face needs at least 3");
  for (size_t k = 0; k < p.indices.size(); ++k)
    if (p.indices[k] < 0 || p.indices[k] >= vertex_count)
      throw InputError(name + " indices[" + std::to_string(k) + "]: " + std::to_string(p.indices[k]) +
                       " is not a vertex index (" + std::to_string(vertex_count) + " vertices)");
  return p;
}

}  // namespace radmesh::python
