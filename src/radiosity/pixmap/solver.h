// The solver's state (PixmapSolver::Impl) and the rows it shoots along,
// shared by the files that make up the solver: solver.cpp (construction
// and the run loop), rows.cpp (a shooter's row, form_factors), narrow.cpp
// (the receivers the hemicube's pixels are too coarse for), display.cpp
// (the display mesh and its values) and state.cpp (the saved state). The
// solver is built once and then only read, so that rows can be computed in
// parallel and every member function but the constructor's helpers is const.
#pragma once

#include "radmesh/pixmap.h"

#include "radiosity/pixmap/hemicube.h"
#include "radiosity/pixmap/texel_geometry.h"
#include "radiosity/transport/visibility.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

namespace radmesh {

namespace internal {

// Texels closer to a shooter's centre than this times the shooter's
// radius (plus a texel) take Lambert's exact form factor (the near field).
constexpr double kNearField = 1.5;

struct RowEntry {
  uint32_t texel;  // global index
  float f;
};

// A shooter's row. The far texels take the hemicube's factor from the
// block as a whole (a narrow pixmap's, Lambert's from the block's centre);
// the near ones, from each of the shooter's texels
// (sh.texels order) by Lambert's formula, so that a block straddling a
// shadow shoots its lit and dark texels' power from where they are. Each
// source texel i delivers far_scale[i] x its power along the far entries,
// which keeps its row's sum at the hemicube's (1 in a closed scene).
struct Row {
  std::vector<RowEntry> far;         // increasing texel; F from the block, before far_scale
  std::vector<uint32_t> near;        // increasing global texel
  std::vector<float> near_f;         // near.size() x sources: F from each source texel
  std::vector<float> far_scale;      // per source texel
  double bytes() const {
    return static_cast<double>(far.size() * sizeof(RowEntry) + near.size() * sizeof(uint32_t) +
                               (near_f.size() + far_scale.size()) * sizeof(float));
  }
};

}  // namespace internal

struct PixmapSolver::Impl {
  const Scene scene;  // a copy: results that hold the solver may outlive the caller's scene
  PixmapOptions options;
  SolveOptions solve;
  Mesh coarse;
  PixmapLayout layout;
  std::vector<HemicubeTriangle> polygons;
  // The texels hold radiosity in float, in units of `unit` (scene units per
  // solver unit): 1, or where the largest emission lies outside [2^-60,
  // 2^60] the power of two that brings it near 1. Radiosity is linear in
  // the emission and a power of two scales exactly, so every emission the
  // scene accepts is carried in float's range, and a scene inside the
  // window is solved exactly as it is.
  double unit = 1.0;
  std::vector<Rgb> rho, emission;           // per pixmap; emission in solver units
  std::vector<int> shooter_of;              // per global texel: its shooter (-1: none)
  double row_budget = 0.0;                  // bytes the rows may take: the cached ones, or one in the making
  double memory_limit = 0.0;                // SolveOptions::max_memory in bytes (for messages)
  Rgb power_emitted{0.0};                   // sum of E x area over the texels, solver units
  Rgb power_enclosed{0.0};                  // E x area of the emitting triangles inside closed objects
  std::vector<std::string> warnings;        // one per emitting patch with such triangles
  // The display mesh: geometry built once.
  Mesh display;
  std::vector<internal::St> display_st;
  std::vector<int> display_pixmap;          // per display vertex
  std::vector<char> display_dark;           // per display vertex: of triangles inside closed objects
  std::vector<long long> display_texel;     // per display triangle: global texel
  // Per pixmap: its display triangles are [display_first[k],
  // display_first[k + 1]), and its lit area's extent, which tells when the
  // pixmap is narrow for a shooter (narrow_receiver).
  std::vector<size_t> display_first;
  struct Extent {
    Vec3 centre{0.0};    // area centroid
    double radius = 0.0;  // farthest vertex from it
    double width = 0.0;   // area / (2 radius): a strip's width, a disc's 1.6 radii
  };
  std::vector<Extent> extent;
  // The lit display triangles of each global owner texel, pieces[
  // pieces_begin[g] .. pieces_begin[g + 1]): the polygons a texel that is
  // not a plain square shoots from, and the parts of a texel a line cuts.
  std::vector<uint32_t> pieces_begin;
  std::vector<int> pieces;
  std::span<const int> pieces_of(long long g) const {
    return {pieces.data() + pieces_begin[static_cast<size_t>(g)],
            static_cast<size_t>(pieces_begin[static_cast<size_t>(g) + 1] - pieces_begin[static_cast<size_t>(g)])};
  }
  // The corners of display triangle d.
  std::array<Vec3, 3> piece_corners(int d) const {
    const auto& t = display.triangles[static_cast<size_t>(d)];
    return {display.positions[t[0]], display.positions[t[1]], display.positions[t[2]]};
  }
  // Shadow rays for the receivers the hemicube's pixels are too coarse for.
  std::unique_ptr<Visibility> vis;

  Impl(const Scene& s, const PixmapOptions& o, const SolveOptions& so) : scene(s), options(o), solve(so) {}

  long long global(int k, int idx) const { return layout.pixmaps[k].first + idx; }
  int pixmap_of_global(long long g) const {
    // Pixmaps are in increasing `first`.
    const auto it = std::upper_bound(layout.pixmaps.begin(), layout.pixmaps.end(), g,
                                     [](long long x, const Pixmap& p) { return x < p.first; });
    return static_cast<int>(it - layout.pixmaps.begin()) - 1;
  }

  // The row of shooter s, its hemicube rendered into `cube`; adds the pixels
  // spread over more than one texel to `spread_pixels` (rows.cpp).
  internal::Row compute_row(int s, Hemicube& cube, long long& spread_pixels) const;
  // NumericalError: shooter s's row would pass row_budget.
  [[noreturn]] void refuse_row(int s) const;
  // What one receiving pixmap takes of a row (rows.cpp).
  struct RowReceiver;

  // Whether pixmap k is too narrow for the pixels of shooter sh's hemicube
  // (`pixel`: their size) or for its near field (`reach`) (narrow.cpp).
  bool narrow_receiver(int k, const Shooter& sh, double pixel, double reach) const;
  // What a narrow pixmap receives from a shooter: its far texels through
  // `add` (far_sum in all), its near ones (within `reach`) from each source
  // texel.
  struct NarrowPart {
    // The share of its factor in front of other surfaces (the rest has open
    // sky behind it): what the hemicube gave those surfaces where it missed
    // the pixmap, the pixmap really hides.
    double behind = 1.0;
    double far_sum = 0.0;
    std::vector<uint32_t> near;   // increasing global texel
    std::vector<float> near_f;    // near.size() x sources
    std::vector<double> exact;    // per source texel: the sum over `near`
  };
  // A source texel's polygon: a plain texel's square, else one of the
  // pieces it owns (a texel along an outline may own a sliver on its far
  // side).
  struct SourcePolygon {
    size_t q;  // its texel, in sh.texels
    std::array<Vec3, 4> v;
    size_t count;
    Vec3 centroid() const {
      Vec3 c(0.0);
      for (size_t m = 0; m < count; ++m) c += v[m];
      return c / static_cast<double>(count);
    }
  };
  std::vector<SourcePolygon> source_polygons(const Shooter& sh) const;
  void receive_narrow(int k, const Shooter& sh, double reach, bool sky, const std::vector<SourcePolygon>& polygons,
                      const std::function<void(int, double)>& add, NarrowPart& out) const;
  // receive_narrow's phases (narrow.cpp).
  struct NarrowReceiver;

  void build_display();

  // The state of a run between shots (solver.cpp).
  struct Shots;
};

}  // namespace radmesh
