// The shooters of a pixmap: its owner texels, block x block at a time,
// split where something stands between them. A shooter's hemicube sits at
// the centroid of its texels and sees from there alone, so a block whose
// texels lie on both sides of a contact line (a wall, an object standing
// on the patch) or of an overhang's outline (a lamp hung under a ceiling)
// is split into groups that each see what their texels see.

#include "radiosity/pixmap/layout.h"
#include "radiosity/pixmap/texel_geometry.h"
#include "radiosity/transport/visibility.h"

namespace radmesh::internal {

namespace {

// The blocks of one pixmap and what splits them.
struct Blocks {
  const Pixmap& pm;
  int k;      // the pixmap
  int b;      // the block's side in texels
  const Visibility* vis;
  std::vector<Shooter>& shooters;
  std::vector<std::pair<St, St>> lines;     // the contact lines, in texel coordinates
  std::vector<std::vector<int>> near_lines;  // per texel: the lines that touch it (empty: no lines)
  std::vector<int> block_lines;             // the lines near any texel of the current block
  std::vector<char> overhung;               // per owner texel

  Blocks(const Pixmap& pm, int k, const std::vector<std::pair<Vec3, Vec3>>& contacts, int block,
         const Visibility* vis, std::vector<Shooter>& shooters);
  char overhung_at(const Vec3& x) const;
  bool separated(int x, int y) const;
  UnionFind groups_of(const std::vector<int>& owners) const;
  void add_shooter(const std::vector<int>& texels);
  void split(int bi, int bj);
};

// Per texel: the lines that touch it (the cost is the lines' length in
// texels); and which owners are overhung.
Blocks::Blocks(const Pixmap& pm, int k, const std::vector<std::pair<Vec3, Vec3>>& contacts, int block,
               const Visibility* vis, std::vector<Shooter>& shooters)
    : pm(pm), k(k), b(block), vis(vis), shooters(shooters) {
  for (const auto& [a, c] : contacts) lines.push_back({st_of(pm, a), st_of(pm, c)});
  if (!lines.empty()) {
    near_lines.resize(static_cast<size_t>(pm.texels()));
    for (size_t e = 0; e < lines.size(); ++e)
      for_each_texel_on(pm, lines[e].first, lines[e].second, [&](int texel) {
        auto& list = near_lines[static_cast<size_t>(texel)];
        if (list.empty() || list.back() != static_cast<int>(e)) list.push_back(static_cast<int>(e));
      });
  }
  overhung.assign(static_cast<size_t>(pm.texels()), 0);
  for (long long idx = 0; idx < pm.texels(); ++idx)
    if (pm.owner[idx] == idx) overhung[idx] = overhung_at(pm.centroid[idx]);
}

// Overhung: a surface (front or back) lies in front of point x of the
// pixmap, along its normal, nearer than a block's diagonal (a lamp hung
// under a ceiling, a low shelf over a floor). One hemicube at a block's
// centroid cannot stand for texels on both sides of an overhang's outline:
// under a lamp 1 cm below a ceiling it sees the lamp's back, which
// receives nothing, and the lit texels of the blocks straddling the lamp's
// outline would lose their power there. So the outline splits a block as
// a contact line does, and a group whose centroid falls on the other side
// (an L of three open texels around a covered one) shoots texel by texel.
char Blocks::overhung_at(const Vec3& x) const {
  const double overhang_reach = std::sqrt(2.0) * b * std::max(pm.texel_u, pm.texel_v);
  return vis && vis->first_hit(x, pm.normal, overhang_reach, pm.patches[0]) >= 0 ? 1 : 0;
}

// Whether the segment between the centroids of texels x and y of a
// block crosses one of the block's contact lines (those near any of its
// texels: the segment stays inside the block).
bool Blocks::separated(int x, int y) const {
  const St p = st_of(pm, pm.centroid[x]), q = st_of(pm, pm.centroid[y]);
  for (int e : block_lines)
    if (segments_cross(p, q, lines[static_cast<size_t>(e)].first, lines[static_cast<size_t>(e)].second)) return true;
  return false;
}

// Groups: owners joined where nothing separates them (neither a contact
// line nor an overhang's outline).
UnionFind Blocks::groups_of(const std::vector<int>& owners) const {
  UnionFind groups(static_cast<int>(owners.size()));
  if (!block_lines.empty()) {
    for (size_t x = 0; x < owners.size(); ++x)
      for (size_t y = x + 1; y < owners.size(); ++y)
        if (overhung[owners[x]] == overhung[owners[y]] && !separated(owners[x], owners[y]))
          groups.unite(static_cast<int>(x), static_cast<int>(y));
  } else {
    int first[2] = {-1, -1};
    for (size_t x = 0; x < owners.size(); ++x) {
      int& f = first[static_cast<size_t>(overhung[owners[x]])];
      if (f < 0) f = static_cast<int>(x);
      groups.unite(f, static_cast<int>(x));
    }
  }
  return groups;
}

void Blocks::add_shooter(const std::vector<int>& texels) {
  Shooter sh;
  sh.pixmap = k;
  sh.texels = texels;
  Vec3 sum(0.0);
  double weight = 0.0;
  for (int idx : texels) {
    sh.area += pm.area[idx];
    sum += pm.coverage[idx] * pm.centroid[idx];
    weight += pm.coverage[idx];
  }
  sh.centre = sum / weight;
  shooters.push_back(std::move(sh));
}

// The shooters of the block whose first texel is (bi, bj): one per group,
// or one per texel of a group whose centroid is not overhung as its texels
// are.
void Blocks::split(int bi, int bj) {
  std::vector<int> owners;
  block_lines.clear();
  for (int j = bj; j < std::min(pm.height, bj + b); ++j)
    for (int i = bi; i < std::min(pm.width, bi + b); ++i) {
      const int idx = j * pm.width + i;
      if (!near_lines.empty())
        block_lines.insert(block_lines.end(), near_lines[static_cast<size_t>(idx)].begin(),
                           near_lines[static_cast<size_t>(idx)].end());
      if (pm.owner[idx] == idx) owners.push_back(idx);
    }
  std::sort(block_lines.begin(), block_lines.end());
  block_lines.erase(std::unique(block_lines.begin(), block_lines.end()), block_lines.end());
  UnionFind groups = groups_of(owners);
  std::vector<int> members;
  for (size_t g = 0; g < owners.size(); ++g) {
    if (groups.find(static_cast<int>(g)) != static_cast<int>(g)) continue;
    members.clear();
    for (size_t x = 0; x < owners.size(); ++x)
      if (groups.find(static_cast<int>(x)) == static_cast<int>(g)) members.push_back(owners[x]);
    add_shooter(members);
    const Shooter& group = shooters.back();
    if (members.size() > 1 && overhung[members[0]] != overhung_at(group.centre)) {
      shooters.pop_back();
      for (int idx : members) add_shooter({idx});
    }
  }
}

}  // namespace

void add_shooters(const Pixmap& pm, int k, const std::vector<std::pair<Vec3, Vec3>>& contacts, int block,
                  const Visibility* vis, std::vector<Shooter>& shooters) {
  Blocks blocks(pm, k, contacts, block, vis, shooters);
  for (int bj = 0; bj < pm.height; bj += block)
    for (int bi = 0; bi < pm.width; bi += block) blocks.split(bi, bj);
}

}  // namespace radmesh::internal
