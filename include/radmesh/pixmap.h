// Pixmap radiosity (Egashira, Sato, Honda & Mima):
// every planar group of patches gets a texel grid in its plane; texels are
// the elements, square blocks of texels the shooters. Progressive refinement
// (Cohen, Chen, Wallace & Greenberg 1988) shoots from the block with the most
// unshot power through a hemicube item buffer of whole polygons; each pixel
// that sees a pixmap spreads its delta form factor over the texels under its
// footprint (virtual oversampling taken to its limit); a pixmap too narrow
// for the pixels, or for the block near it, takes exact factors instead.
// The state (radiosity and unshot radiosity per texel, in float) can be
// saved and resumed bit for bit.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/mesh.h"
#include "radmesh/method.h"
#include "radmesh/progress.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace radmesh {

struct PixmapOptions {
  // Texel edge in scene units (0: scene diagonal / 80). Each pixmap
  // stretches it to fit its extent exactly, and coarsens it where the
  // pixmap would exceed max_texels.
  double texel_size = 0.0;
  long long max_texels = 1 << 20;  // per pixmap
  int hemicube_res = 128;          // pixels along the top face's side
  int block = 4;                   // a shooter is block x block texels
  // Stop when the unshot power is at most this fraction of the emitted
  // power, or after `shots` shots in all (0: no limit), whichever is first.
  double unshot = 1e-4;
  long long shots = 0;
  // The method's result as it stands every this many shots, counted over
  // resumes (SolveCallbacks::on_round; 0: none).
  long long snapshot_every = 0;
};

// The options a user sets, with their ranges (the radmesh program's flags,
// the checks of PixmapSolver and radmesh::solve).
const OptionTable<PixmapOptions>& pixmap_option_table();

// One texel grid: x(s, t) = origin + s texel_u u + t texel_v v, for texel
// coordinates s in [0, width], t in [0, height]; texel (i, j) has index
// j * width + i.
struct Pixmap {
  std::vector<int> patches;  // the scene patches it covers: coplanar, one material, connected
  int material = -1;
  Vec3 origin{0.0}, u{0.0}, v{0.0}, normal{0.0};
  double texel_u = 0.0, texel_v = 0.0;
  int width = 0, height = 0;
  long long first = 0;              // index of texel 0 among all texels of the layout
  std::vector<double> coverage;     // per texel: area of the patches inside it (outside closed objects)
  std::vector<Vec3> centroid;       // per texel: centroid of that area
  // Per texel: the texel that holds its value (itself, or for a texel less
  // than a quarter covered the most covered neighbour, so that slivers at
  // borders do not get the aliasing of a tiny area); -1 when not covered.
  std::vector<int> owner;
  std::vector<double> area;         // per texel: its area plus the slivers it holds (0 when owned)
  std::vector<char> whole;          // per texel: an owner wholly covered (area >= texel area: it may hold slivers)
  // Texels a contact line cuts into parts (a thin wall standing across
  // them): each part is a set of triangles of the layout's coarse mesh (the
  // patches cut along their contact lines), held by the texel's owner or,
  // all but the largest, by a neighbour on the part's side. Sorted by texel.
  struct Cut {
    int texel = -1;
    std::vector<std::vector<int>> triangles;  // per part
    std::vector<int> owners;                  // per part
  };
  std::vector<Cut> cuts;
  // Wall feet: the edges between two of this pixmap's triangles that a
  // third, another pixmap's, shares (a wall standing on it), in texel
  // coordinates; per texel whether one touches it, edges included (empty
  // where there is none), and (texel, foot) for each such touch, sorted.
  struct Foot {
    double s0, t0, s1, t1;
  };
  std::vector<Foot> feet;
  std::vector<char> wall_foot;
  std::vector<std::pair<int, int>> foot_at;

  long long texels() const { return static_cast<long long>(width) * height; }
  // Texel coordinates (s, t) of point x of the plane.
  double s_of(const Vec3& x) const { return glm::dot(x - origin, u) / texel_u; }
  double t_of(const Vec3& x) const { return glm::dot(x - origin, v) / texel_v; }
};

// A block of texels of one pixmap that shoots as one: its hemicube sits at
// the area centroid of its texels.
struct Shooter {
  int pixmap = -1;
  std::vector<int> texels;  // owners of the block (indices within the pixmap)
  Vec3 centre{0.0};
  double area = 0.0;
};

struct PixmapLayout {
  std::vector<Pixmap> pixmaps;
  std::vector<int> pixmap_of_patch;  // per scene patch
  std::vector<Shooter> shooters;
  long long texels = 0;              // all texels of all grids
  long long covered = 0;             // texels holding a value (owners)
  // Area of the patches left out because it lies inside closed objects
  // standing on them (the floor under a block): no light reaches it.
  double enclosed_area = 0.0;
  // Per triangle of the coarse mesh the layout was made from (the patches cut
  // along their contact lines): 1 when it lies inside a closed object.
  std::vector<char> enclosed;
  double texel_size = 0.0;           // the texel size asked for (resolved)
};

// What the pixmap method meshes: every patch cut along its contact lines
// (where another patch stands on it or passes through), no finer than the
// mesher's angle bound needs. Each triangle then lies wholly inside or
// outside every closed object standing on its patch.
MeshingOptions pixmap_meshing_options(const Scene& scene);

// The texel grids of a scene. Throws InputError when the options are out of
// range and NumericalError when the texels would not fit in `memory_bytes`.
PixmapLayout make_pixmap_layout(const Scene& scene, const PixmapOptions& options, double memory_bytes);

// The saved state of a run: enough to resume it bit for bit
// (MethodState::source: where it was read from, for messages; not saved).
struct PixmapState : MethodState {
  long long shots = 0;
  // Per pixmap, 3 floats per texel (RGB): radiosity without the ambient
  // term, and the unshot radiosity. Texels that are not owners hold 0.
  std::vector<std::vector<float>> radiosity, unshot;
  Rgb power_absorbed{0.0}, power_escaped{0.0};  // so far
  // What the state was made from; a resume with other values is refused.
  std::string scene_fingerprint;
  double texel_size = 0.0;
  long long max_texels = 0;
  int hemicube_res = 0, block = 0;
  std::vector<std::array<int, 2>> sizes;  // per pixmap: width, height
};

// A digest of the geometry and materials of a scene (hex): equal for equal scenes.
std::string scene_fingerprint(const Scene& scene);

// InputError saying what differs when `state` was not made by `layout` and
// `options` on `scene` (`where` names the state in the message).
void check_resumable(const PixmapState& state, const Scene& scene, const PixmapLayout& layout,
                     const PixmapOptions& options, const std::string& where);

// What a run ends with. Its state, ambient term and powers are in the
// solver's units (PixmapSolver::unit).
struct PixmapRun {
  PixmapState state;
  bool interrupted = false;   // stopped by the cancel flag
  long long shots_this_run = 0;
  long long rows_computed = 0;  // hemicubes rendered
  long long rows_cached = 0;    // rows kept for later shots
  long long pixels_spread = 0;  // pixels whose footprint covers more than one texel
  double unshot_fraction = 0.0;  // unshot power / emitted power (sum of channels)
  Rgb ambient{0.0};              // Cohen et al.'s ambient radiosity at the end
  std::array<double, 3> residual{0, 0, 0};  // max unshot / max radiosity per channel
  Rgb power_emitted{0.0};
  double seconds_hemicubes = 0.0, seconds_shots = 0.0;
};

struct PixmapCallbacks {
  ProgressFn progress;
  // Polled between shots: true stops the run (the state stays consistent).
  std::function<bool()> cancelled;
  // Called every `snapshot_every` shots (counted over resumes) with the state.
  long long snapshot_every = 0;
  std::function<void(const PixmapState&)> on_snapshot;
};

class PixmapSolver {
public:
  // Keeps a copy of `scene`. Builds the layout and display mesh on
  // the patches cut along their contact lines (pixmap_meshing_options), and
  // the polygons the hemicube renders (the patches' coarsest triangulation).
  PixmapSolver(const Scene& scene, const PixmapOptions& options, const SolveOptions& solve);
  ~PixmapSolver();
  PixmapSolver(const PixmapSolver&) = delete;
  PixmapSolver& operator=(const PixmapSolver&) = delete;

  const Scene& scene() const;  // the solver's copy
  const PixmapLayout& layout() const;
  // Emitted power: E x area summed over the texels (the patches' E x area,
  // less the parts inside closed objects).
  Rgb power_emitted() const;
  // What the parts of emitting patches inside closed objects emit (E x
  // area): it goes into the objects, which no texel covers, and the method
  // counts it as emitted and escaped, as the other methods do; and one
  // warning per such patch (enclosed_emitter_warnings).
  Rgb power_enclosed() const;
  // Scene units of radiosity per unit of the solver's: the states, the
  // texel values of display() and ambient() are in the solver's units, and
  // display_mesh(), power_emitted() and power_enclosed() in the scene's. 1
  // unless the scene's largest emission lies outside [2^-60, 2^60], where it
  // is the power of two that brings that emission near 1 (float, which the
  // texels are held in, could not carry it).
  double unit() const;
  const std::vector<std::string>& warnings() const;
  // The state before any shot: B = unshot = E.
  PixmapState initial_state() const;
  // Shoots from `start` (initial_state() or a checked saved state) until the
  // unshot fraction or the shot count of the options is reached.
  PixmapRun run(PixmapState start, const PixmapCallbacks& callbacks = {}) const;

  // Form factors from each texel of shooter `s` (in Shooter::texels order)
  // to texels, (global texel index, F) in increasing texel order, as the
  // shots use them: a source texel's power times F reaches the texel.
  std::vector<std::vector<std::pair<long long, double>>> form_factors(int s) const;

  // Radiosity per texel for display: the state plus rho times `ambient`,
  // owners' values copied to the texels they hold (per pixmap, RGB floats
  // as in the state).
  std::vector<std::vector<float>> display(const PixmapState& state, const Rgb& ambient) const;
  // Cohen et al.'s ambient term of a state.
  Rgb ambient(const PixmapState& state) const;

  // The display mesh, triangles cut at texel boundaries (each lies in one
  // texel), and the solution on it: element values are their texel's (its
  // owner's; 0 and texel -1 inside closed objects),
  // vertex values the bilinear interpolation of texel centres (covered
  // texels only), per pixmap (never averaged across pixmaps).
  void display_mesh(const std::vector<std::vector<float>>& texels, Mesh& mesh, Solution& solution,
                    std::vector<int>& texel_of_triangle) const;
  // Per display vertex, its texel coordinates (s, t) divided by the
  // pixmap's size (the lightmap's u, v) and its pixmap, in the order of
  // display_mesh's nodal points.
  void display_uv(std::vector<std::array<double, 2>>& uv, std::vector<int>& pixmap) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radmesh
