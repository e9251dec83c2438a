// Probe files: one probe a line, `label x y z nx ny nz`; '#' starts a comment.
#pragma once

#include "radmesh/probe.h"

#include <string>
#include <vector>

namespace radmesh {

// Throws InputError naming file:line and the bad value.
std::vector<Probe> read_probes(const std::string& path);

// CSV with header label,x,y,z,nx,ny,nz,patch,r,g,b. Written to a temporary
// file and renamed. Throws IoError.
void write_probe_csv(const std::string& path, const Scene& scene, const std::vector<Probe>& probes,
                     const std::vector<ProbeResult>& results);

}  // namespace radmesh
