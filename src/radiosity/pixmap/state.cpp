// The state of a run (PixmapState): the one before any shot, the ambient
// term a state implies, and the checks that let a saved state resume a run.
// A state is only texel values, so it can resume a run bit for bit only on
// the same layout: the scene's fingerprint and every option that shapes
// the layout are saved with it, and a resume compares them first.

#include "radiosity/pixmap/solver.h"

#include "radmesh/errors.h"
#include "core/fnv.h"

#include <cmath>

namespace radmesh {

std::string scene_fingerprint(const Scene& scene) {
  internal::Fnv1a h;
  auto mix_int = [&](long long v) { h.add(&v, sizeof v); };
  auto mix_vec = [&](const Vec3& v) {
    for (int c = 0; c < 3; ++c) {
      const double d = v[c] == 0.0 ? 0.0 : v[c];  // -0 and 0 alike
      h.add(&d, sizeof d);
    }
  };
  mix_int(static_cast<long long>(scene.vertices.size()));
  for (const Vec3& v : scene.vertices) mix_vec(v);
  mix_int(static_cast<long long>(scene.materials.size()));
  for (const Material& m : scene.materials) {
    mix_vec(m.reflectance);
    mix_vec(m.emission);
  }
  mix_int(static_cast<long long>(scene.patches.size()));
  for (const Patch& p : scene.patches) {
    mix_int(p.material);
    mix_int(static_cast<long long>(p.outer.size()));
    for (int v : p.outer) mix_int(v);
    mix_int(static_cast<long long>(p.holes.size()));
    for (const auto& hole : p.holes) {
      mix_int(static_cast<long long>(hole.size()));
      for (int v : hole) mix_int(v);
    }
  }
  return h.hex();
}

void check_resumable(const PixmapState& state, const Scene& scene, const PixmapLayout& layout,
                     const PixmapOptions& options, const std::string& where) {
  auto refuse = [&](const std::string& why) {
    throw InputError(where + ": cannot resume: " + why, {"texel_size", "max_texels", "hemicube_res", "block"});
  };
  if (state.scene_fingerprint != scene_fingerprint(scene))
    refuse("it was made from another scene (or this one edited): fingerprint " + state.scene_fingerprint +
           ", this scene " + scene_fingerprint(scene));
  auto same = [&](const char* option, double saved, double now) {
    if (saved != now)
      refuse(std::string("it was made with ") + option + " " + format_number(saved) + ", this run has " + option +
             " " + format_number(now));
  };
  same("texel_size", state.texel_size, layout.texel_size);
  same("max_texels", static_cast<double>(state.max_texels), static_cast<double>(options.max_texels));
  same("hemicube_res", state.hemicube_res, options.hemicube_res);
  same("block", state.block, options.block);
  if (state.sizes.size() != layout.pixmaps.size())
    refuse(std::to_string(state.sizes.size()) + " pixmaps saved, this layout has " +
           std::to_string(layout.pixmaps.size()));
  for (size_t k = 0; k < layout.pixmaps.size(); ++k) {
    const Pixmap& pm = layout.pixmaps[k];
    const size_t n = static_cast<size_t>(pm.texels()) * 3;
    if (state.sizes[k][0] != pm.width || state.sizes[k][1] != pm.height || state.radiosity[k].size() != n ||
        state.unshot[k].size() != n)
      refuse("pixmap " + std::to_string(k) + " is " + std::to_string(state.sizes[k][0]) + " x " +
             std::to_string(state.sizes[k][1]) + " texels in the state, " + std::to_string(pm.width) + " x " +
             std::to_string(pm.height) + " here");
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(state.radiosity[k][i]) || !std::isfinite(state.unshot[k][i]) ||
          state.radiosity[k][i] < 0.0f || state.unshot[k][i] < 0.0f)
        refuse("pixmap " + std::to_string(k) + " texel " + std::to_string(i / 3) + " holds a negative or non-finite value");
  }
  if (state.shots < 0) refuse("a negative shot count");
}

PixmapState PixmapSolver::initial_state() const {
  const Impl& m = *impl_;
  PixmapState st;
  st.scene_fingerprint = scene_fingerprint(m.scene);
  st.texel_size = m.layout.texel_size;
  st.max_texels = m.options.max_texels;
  st.hemicube_res = m.options.hemicube_res;
  st.block = m.options.block;
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    st.sizes.push_back({pm.width, pm.height});
    std::vector<float> b(static_cast<size_t>(pm.texels()) * 3, 0.0f);
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i)
        for (int c = 0; c < 3; ++c) b[i * 3 + c] = static_cast<float>(m.emission[k][c]);
    st.radiosity.push_back(b);
    st.unshot.push_back(std::move(b));
  }
  return st;
}

Rgb PixmapSolver::ambient(const PixmapState& state) const {
  // Cohen et al. 1988: the unshot power spread over the scene's area,
  // times the interreflection factor 1 / (1 - mean rho); in an open scene
  // only the share of it that stays, taken as the share of the power ended
  // so far that was absorbed rather than escaped, so that the power the
  // ambient term absorbs is what the unshot power will leave in the scene.
  const Impl& m = *impl_;
  Rgb unshot(0.0), rho_area(0.0);
  double area = 0.0;
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i) {
        for (int c = 0; c < 3; ++c) unshot[c] += static_cast<double>(state.unshot[k][i * 3 + c]) * pm.area[i];
        rho_area += m.rho[k] * pm.area[i];
        area += pm.area[i];
      }
  }
  if (!(area > 0.0)) return Rgb(0.0);
  Rgb amb(0.0);
  for (int c = 0; c < 3; ++c) {
    const double ended = state.power_absorbed[c] + state.power_escaped[c];
    const double stays = ended > 0.0 ? state.power_absorbed[c] / ended : 1.0;
    amb[c] = stays * unshot[c] / area / (1.0 - rho_area[c] / area);
  }
  return amb;
}

}  // namespace radmesh
