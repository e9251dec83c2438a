// The layout's internal entry points, shared by layout.cpp (the grids),
// shooters.cpp (the blocks) and the solver: the layout of a scene on a
// given coarse mesh, the mesh the method lays its grids on, the options
// check, and the memory a texel costs. The solver builds the layout on
// the coarse mesh it keeps (its cuts name that mesh's triangles), which is
// why layout_of takes the mesh rather than making it.
#pragma once

#include "radmesh/pixmap.h"

#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

namespace radmesh {
class Visibility;
}

namespace radmesh::internal {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// What a pixmap run holds per texel at its peak, besides the cached rows:
// the texel grids and state, the display mesh and its values, and the
// radiosity.vtu being written, of which the grids alone are about 90 bytes.
// Taken from the peak resident memory over texels of large runs with one
// shot, rounded up.
constexpr double kBytesPerTexel = 700.0;

// InputError unless the options are in range.
void check_options(const PixmapOptions& o);

// The texel grids of `scene` on `coarse` (the patches cut along their
// contact lines); `vis` finds the triangles inside closed objects and the
// overhung texels (none when null). NumericalError when the texels would
// not fit in `memory_bytes`.
PixmapLayout layout_of(const Scene& scene, const Mesh& coarse, const PixmapOptions& options, double memory_bytes,
                       const Visibility* vis);

// The method's mesh (pixmap_meshing_options): the dark part under a block
// follows the block's outline exactly.
Mesh outline_triangulation(const Scene& scene);

// Appends the shooters of pixmap k (its owners, block x block texels at a
// time) to `shooters`, split along `contacts` (the contact lines inside
// the pixmap, world points) and along the outlines of overhangs.
void add_shooters(const Pixmap& pm, int k, const std::vector<std::pair<Vec3, Vec3>>& contacts, int block,
                  const Visibility* vis, std::vector<Shooter>& shooters);

}  // namespace radmesh::internal
