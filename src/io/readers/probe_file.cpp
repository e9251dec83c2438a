// The probe file (lines "label x y z nx ny nz"), read with every value
// checked, and probes.csv, the values found there.

#include "radmesh/probe_file.h"

#include "io/writers/atomic_file.h"
#include "io/readers/scene_sources.h"
#include "core/text_syntax.h"
#include "io/writers/json_file.h"
#include "radmesh/errors.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace radmesh {

std::vector<Probe> read_probes(const std::string& path) {
  internal::check_input_file(path, "a probe file");
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open probe file");
  std::vector<Probe> probes;
  int ln = 0;
  for (std::string line; std::getline(in, line);) {
    ++ln;
    if (ln == 1) internal::strip_byte_order_mark(line);
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream s(line);
    std::vector<std::string> tok;
    for (std::string t; s >> t;) tok.push_back(t);
    if (tok.empty()) continue;
    if (tok.size() != 7)
      throw InputError(where(path, ln) + "expected 'label x y z nx ny nz', got " + std::to_string(tok.size()) +
                       " fields");
    double v[6];
    for (int k = 0; k < 6; ++k) {
      const std::string& t = tok[static_cast<size_t>(k) + 1];
      const std::string why = internal::read_number(t, &v[k]);
      if (!why.empty()) throw InputError(where(path, ln) + "value '" + internal::shown(t) + "' " + why);
    }
    Probe p;
    p.label = tok[0];
    p.point = Vec3(v[0], v[1], v[2]);
    const Vec3 n(v[3], v[4], v[5]);
    if (glm::length(n) == 0.0) throw InputError(where(path, ln) + "probe '" + p.label + "' has a zero normal");
    p.normal = glm::normalize(n);
    p.file = path;
    p.line = ln;
    probes.push_back(p);
  }
  if (probes.empty()) throw InputError(path + ": no probes in file");
  return probes;
}

void write_probe_csv(const std::string& path, const Scene& scene, const std::vector<Probe>& probes,
                     const std::vector<ProbeResult>& results) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "label,x,y,z,nx,ny,nz,patch,r,g,b\n" << std::setprecision(10);
    for (size_t k = 0; k < probes.size(); ++k) {
      const Probe& p = probes[k];
      const ProbeResult& r = results[k];
      out << csv_field(p.label) << ',' << p.point.x << ',' << p.point.y << ',' << p.point.z << ',' << p.normal.x << ','
          << p.normal.y << ',' << p.normal.z << ',' << csv_field(scene.patches[static_cast<size_t>(r.patch)].name) << ','
          << r.radiosity.x << ',' << r.radiosity.y << ',' << r.radiosity.z << '\n';
    }
  });
}

}  // namespace radmesh
