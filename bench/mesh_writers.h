// Plain writers of one polygon mesh in every format radmesh reads, for the
// reader tests and the load-time benchmark: the same positions (float, so that every reader, float or
// double, sees the same numbers when they are exact in float) and the same
// faces in the same order.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace radmesh::test {

struct PolyMesh {
  std::vector<std::array<float, 3>> positions;
  std::vector<std::vector<uint32_t>> faces;  // 0-based, any vertex count (triangles for STL, glTF)
};

// Shortest text that reads back as the same float; integers as integers.
inline std::string number(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(v));
  return buf;
}

inline std::ofstream open_out(const std::filesystem::path& p, bool binary = false) {
  std::ofstream out(p, binary ? std::ios::binary : std::ios::out);
  if (!out) throw std::runtime_error("cannot write " + p.string());
  return out;
}

template <class T>
void put(std::ostream& out, T v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);  // little-endian machines only
}

// OBJ with one object `name`; `usemtl` + `mtllib` when material is given.
inline void write_obj(const std::filesystem::path& p, const PolyMesh& m, const std::string& name,
                      const std::string& mtllib = "", const std::string& material = "") {
  auto out = open_out(p);
  if (!mtllib.empty()) out << "mtllib " << mtllib << "\n";
  for (const auto& v : m.positions) out << "v " << number(v[0]) << " " << number(v[1]) << " " << number(v[2]) << "\n";
  out << "o " << name << "\n";
  if (!material.empty()) out << "usemtl " << material << "\n";
  for (const auto& f : m.faces) {
    out << "f";
    for (uint32_t i : f) out << " " << i + 1;
    out << "\n";
  }
}

inline void write_ply(const std::filesystem::path& p, const PolyMesh& m, bool binary) {
  auto out = open_out(p, binary);
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "element vertex " << m.positions.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "element face " << m.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : m.positions) {
    if (binary)
      for (float c : v) put(out, c);
    else
      out << number(v[0]) << " " << number(v[1]) << " " << number(v[2]) << "\n";
  }
  for (const auto& f : m.faces) {
    if (binary) {
      put(out, static_cast<uint8_t>(f.size()));
      for (uint32_t i : f) put(out, static_cast<int32_t>(i));
    } else {
      out << f.size();
      for (uint32_t i : f) out << " " << i;
      out << "\n";
    }
  }
}

inline void write_off(const std::filesystem::path& p, const PolyMesh& m) {
  auto out = open_out(p);
  out << "OFF\n" << m.positions.size() << " " << m.faces.size() << " 0\n";
  for (const auto& v : m.positions) out << number(v[0]) << " " << number(v[1]) << " " << number(v[2]) << "\n";
  for (const auto& f : m.faces) {
    out << f.size();
    for (uint32_t i : f) out << " " << i;
    out << "\n";
  }
}

inline void write_stl(const std::filesystem::path& p, const PolyMesh& m, bool binary, const std::string& name) {
  auto out = open_out(p, binary);
  if (binary) {
    char header[80] = {};
    std::memcpy(header, name.data(), std::min<size_t>(name.size(), 79));  // must not start with "solid"
    out.write(header, 80);
    put(out, static_cast<uint32_t>(m.faces.size()));
  } else {
    out << "solid " << name << "\n";
  }
  for (const auto& f : m.faces) {
    if (f.size() != 3) throw std::runtime_error("STL holds triangles only");
    if (binary) {
      for (int k = 0; k < 3; ++k) put(out, 0.0f);  // normal: readers compute their own
      for (uint32_t i : f)
        for (float c : m.positions[i]) put(out, c);
      put(out, static_cast<uint16_t>(0));
    } else {
      out << "facet normal 0 0 0\nouter loop\n";
      for (uint32_t i : f) {
        const auto& v = m.positions[i];
        out << "vertex " << number(v[0]) << " " << number(v[1]) << " " << number(v[2]) << "\n";
      }
      out << "endloop\nendfacet\n";
    }
  }
  if (!binary) out << "endsolid " << name << "\n";
}

// glTF 2.0 material for write_gltf: factors as given (no clamping here).
struct GltfMaterial {
  std::string name;
  std::array<double, 4> base{0.5, 0.5, 0.5, 1.0};
  bool has_base = true;
  std::array<double, 3> emissive{0, 0, 0};
  double strength = 1.0;  // KHR_materials_emissive_strength when != 1
};

// glTF 2.0, one node `name` with one mesh of one triangle primitive; with a
// material when `material` is given. `node_extra` is added to the node
// (e.g. "\"translation\": [1, 2, 3]"). `.glb` when glb, else `.gltf` + `.bin`.
inline void write_gltf(const std::filesystem::path& p, const PolyMesh& m, const std::string& name, bool glb,
                       const GltfMaterial* material = nullptr, const std::string& node_extra = "") {
  std::string bin;
  auto add = [&](const void* d, size_t n) { bin.append(static_cast<const char*>(d), n); };
  std::array<float, 3> lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (const auto& v : m.positions) {
    add(v.data(), 12);
    for (int k = 0; k < 3; ++k) {
      lo[static_cast<size_t>(k)] = std::min(lo[static_cast<size_t>(k)], v[static_cast<size_t>(k)]);
      hi[static_cast<size_t>(k)] = std::max(hi[static_cast<size_t>(k)], v[static_cast<size_t>(k)]);
    }
  }
  const size_t index_offset = bin.size();
  size_t count = 0;
  for (const auto& f : m.faces) {
    if (f.size() != 3) throw std::runtime_error("glTF holds triangles only");
    for (uint32_t i : f) add(&i, 4);
    count += 3;
  }
  while (bin.size() % 4) bin.push_back('\0');
  std::ostringstream j;
  j.precision(17);
  j << "{\"asset\": {\"version\": \"2.0\"},\n \"buffers\": [{\"byteLength\": " << bin.size();
  const std::string bin_name = p.stem().string() + ".bin";
  if (!glb) j << ", \"uri\": \"" << bin_name << "\"";
  j << "}],\n \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": " << index_offset
    << "}, {\"buffer\": 0, \"byteOffset\": " << index_offset << ", \"byteLength\": " << count * 4 << "}],\n"
    << " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": " << m.positions.size()
    << ", \"type\": \"VEC3\", \"min\": [" << number(lo[0]) << ", " << number(lo[1]) << ", " << number(lo[2])
    << "], \"max\": [" << number(hi[0]) << ", " << number(hi[1]) << ", " << number(hi[2]) << "]},\n"
    << "   {\"bufferView\": 1, \"componentType\": 5125, \"count\": " << count << ", \"type\": \"SCALAR\"}],\n";
  if (material) {
    j << " \"materials\": [{\"name\": \"" << material->name << "\"";
    if (material->has_base)
      j << ", \"pbrMetallicRoughness\": {\"baseColorFactor\": [" << material->base[0] << ", " << material->base[1]
        << ", " << material->base[2] << ", " << material->base[3] << "]}";
    j << ", \"emissiveFactor\": [" << material->emissive[0] << ", " << material->emissive[1] << ", "
      << material->emissive[2] << "]";
    if (material->strength != 1.0)
      j << ", \"extensions\": {\"KHR_materials_emissive_strength\": {\"emissiveStrength\": " << material->strength
        << "}}";
    j << "}],\n";
    if (material->strength != 1.0) j << " \"extensionsUsed\": [\"KHR_materials_emissive_strength\"],\n";
  }
  j << " \"meshes\": [{\"name\": \"" << name << "\", \"primitives\": [{\"attributes\": {\"POSITION\": 0}, "
    << "\"indices\": 1" << (material ? ", \"material\": 0" : "") << "}]}],\n"
    << " \"nodes\": [{\"name\": \"" << name << "\", \"mesh\": 0" << (node_extra.empty() ? "" : ", " + node_extra)
    << "}],\n \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n";
  std::string json = j.str();
  if (!glb) {
    auto out = open_out(p);
    out << json;
    auto b = open_out(p.parent_path() / bin_name, true);
    b.write(bin.data(), static_cast<std::streamsize>(bin.size()));
    return;
  }
  while (json.size() % 4) json.push_back(' ');
  auto out = open_out(p, true);
  put(out, 0x46546C67u);
  put(out, 2u);
  put(out, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  put(out, static_cast<uint32_t>(json.size()));
  put(out, 0x4E4F534Au);
  out.write(json.data(), static_cast<std::streamsize>(json.size()));
  put(out, static_cast<uint32_t>(bin.size()));
  put(out, 0x004E4942u);
  out.write(bin.data(), static_cast<std::streamsize>(bin.size()));
}

// The unit icosphere of 20 x 4^level triangles (each level splits every
// triangle in four at its edge midpoints, pushed out to the sphere),
// counter-clockwise seen from outside. Double precision.
// Cuts every triangle into four at its edges' midpoints (each edge's
// midpoint made once, passed through `place`: the identity keeps the
// surface, a projection pushes it out to a sphere), keeping each
// triangle's orientation.
template <class Place>
void subdivide_at_midpoints(std::vector<std::array<double, 3>>& positions, std::vector<std::array<int, 3>>& triangles,
                            Place&& place) {
  std::map<std::pair<int, int>, int> mid;
  auto m = [&](int a, int b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    if (auto it = mid.find(key); it != mid.end()) return it->second;
    const auto& pa = positions[static_cast<size_t>(a)];
    const auto& pb = positions[static_cast<size_t>(b)];
    positions.push_back(place(std::array<double, 3>{0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])}));
    return mid[key] = static_cast<int>(positions.size()) - 1;
  };
  std::vector<std::array<int, 3>> next;
  next.reserve(4 * triangles.size());
  for (const auto& [a, b, c] : triangles) {
    const int ab = m(a, b), bc = m(b, c), ca = m(c, a);
    next.push_back({a, ab, ca});
    next.push_back({b, bc, ab});
    next.push_back({c, ca, bc});
    next.push_back({ab, bc, ca});
  }
  triangles.swap(next);
}

struct Icosphere {
  std::vector<std::array<double, 3>> positions;
  std::vector<std::array<int, 3>> triangles;  // 0-based
};
inline Icosphere icosphere(int level) {
  auto unit = [](std::array<double, 3> p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / n, p[1] / n, p[2] / n};
  };
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Icosphere s;
  s.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : s.positions) p = unit(p);
  s.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9},  {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},   {3, 4, 2},  {3, 2, 6},   {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) subdivide_at_midpoints(s.positions, s.triangles, unit);
  return s;
}

// An n x n grid of quads over a bumpy height field, 2 triangles each.
inline PolyMesh grid(int n) {
  PolyMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.push_back({0.5f * static_cast<float>(i), 0.125f * static_cast<float>((i * 7 + j * 3) % 11),
                             0.25f * static_cast<float>(j)});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<uint32_t>(j * (n + 1) + i), b = a + 1, c = a + static_cast<uint32_t>(n) + 2,
                 d = a + static_cast<uint32_t>(n) + 1;
      m.faces.push_back({a, c, b});
      m.faces.push_back({a, d, c});
    }
  return m;
}

// Writes `m` as `stem.ext` in `dir` in every format; returns the file names.
inline std::vector<std::string> write_every_format(const std::filesystem::path& dir, const PolyMesh& m,
                                                   const std::string& stem) {
  write_obj(dir / (stem + ".obj"), m, stem);
  write_ply(dir / (stem + "_ascii.ply"), m, false);
  write_ply(dir / (stem + "_binary.ply"), m, true);
  write_off(dir / (stem + ".off"), m);
  write_stl(dir / (stem + "_ascii.stl"), m, false, stem);
  write_stl(dir / (stem + "_binary.stl"), m, true, stem);
  write_gltf(dir / (stem + ".gltf"), m, stem, false);
  write_gltf(dir / (stem + ".glb"), m, stem, true);
  return {stem + ".obj",         stem + "_ascii.ply",  stem + "_binary.ply", stem + ".off",
          stem + "_ascii.stl",   stem + "_binary.stl", stem + ".gltf",       stem + ".glb"};
}

}  // namespace radmesh::test
