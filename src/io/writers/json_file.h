// The summary as a JSON document, and JSON and CSV text written the way
// every radmesh file is (atomically; names quoted where they must be).
#pragma once

#include "radmesh/summary.h"

#include <nlohmann/json.hpp>

#include <string>

namespace radmesh {

// The document write_summary writes.
nlohmann::json make_summary(const RunInfo& info, const Scene& scene, const Mesh& mesh,
                            const TriangleQuality& quality, const MethodResult* result);

// Writes JSON atomically (tmp + rename). Throws IoError.
void write_json(const std::string& path, const nlohmann::json& doc);

// A CSV field: quoted (quotes doubled) when it holds a comma, a quote or a
// line break (patch, material and probe names in patches.csv, probes.csv).
std::string csv_field(const std::string& text);

}  // namespace radmesh
