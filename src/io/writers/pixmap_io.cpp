// The pixmap method's state and lightmaps as files (VTK image data, PNG,
// JSON, OBJ + MTL).

#include "io/writers/pixmap_io.h"

#include "io/writers/atomic_file.h"
#include "io/readers/json_parse.h"
#include "io/writers/json_file.h"
#include "io/writers/vtk_file.h"
#include "radmesh/errors.h"
#include "core/fnv.h"

#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLImageDataWriter.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace radmesh {

namespace fs = std::filesystem;

namespace {

std::string pixmap_file(size_t k, const char* ext) { return "pixmap_" + std::to_string(k) + ext; }

vtkNew<vtkFloatArray> float_cells(const char* name, const std::vector<float>& values, int components) {
  vtkNew<vtkFloatArray> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / static_cast<size_t>(components)));
  std::copy(values.begin(), values.end(), a->GetPointer(0));
  return a;
}

nlohmann::json vec(const Vec3& v) { return {v.x, v.y, v.z}; }

// The state's checksum: its JSON (without the checksum) and every pixmap's
// radiosity and unshot texels, so that a resume refuses a state whose
// figures were damaged or edited, or whose pixmap files were swapped,
// instead of continuing from it. (The texel files' zlib blocks carry their
// own checks; state.json carries none.)
std::string state_checksum(nlohmann::json doc, const std::vector<std::vector<float>>& radiosity,
                           const std::vector<std::vector<float>>& unshot) {
  doc.erase("checksum");
  internal::Fnv1a h;
  const std::string text = doc.dump();
  h.add(text.data(), text.size());
  for (size_t k = 0; k < radiosity.size(); ++k) {
    h.add(radiosity[k].data(), radiosity[k].size() * sizeof(float));
    h.add(unshot[k].data(), unshot[k].size() * sizeof(float));
  }
  return h.hex();
}

}  // namespace

std::vector<std::string> write_pixmap_state(const std::string& out_dir, const PixmapOutput& out) {
  const Scene& scene = out.solver->scene();
  const PixmapLayout& L = out.solver->layout();
  const PixmapState& st = out.state;
  const fs::path dir = fs::path(out_dir) / "pixmaps";
  std::vector<std::string> names;
  for (size_t k = 0; k < L.pixmaps.size(); ++k) names.push_back(pixmap_file(k, ".vti"));
  names.push_back("state.json");
  internal::prepare_output_dir(dir.string(), R"(pixmap_[0-9]+\.vti|state\.json)", names);
  std::vector<std::string> written;
  nlohmann::json doc;
  doc["format"] = "radmesh pixmap state";
  doc["version"] = 3;
  doc["scene"] = scene.source;
  doc["scene_fingerprint"] = st.scene_fingerprint;
  doc["shots"] = st.shots;
  doc["options"] = {{"texel_size", st.texel_size},       {"max_texels", st.max_texels},
                    {"hemicube_res", st.hemicube_res},   {"block", st.block}};
  doc["power_absorbed"] = vec(st.power_absorbed);
  doc["power_escaped"] = vec(st.power_escaped);
  doc["pixmaps"] = nlohmann::json::array();
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    const Pixmap& pm = L.pixmaps[k];
    vtkNew<vtkImageData> image;
    image->SetDimensions(pm.width + 1, pm.height + 1, 1);
    image->SetOrigin(pm.origin.x, pm.origin.y, pm.origin.z);
    image->SetSpacing(pm.texel_u, pm.texel_v, 1.0);
    const double direction[9] = {pm.u.x, pm.v.x, pm.normal.x, pm.u.y, pm.v.y, pm.normal.y,
                                 pm.u.z, pm.v.z, pm.normal.z};
    image->SetDirectionMatrix(direction);
    image->GetCellData()->AddArray(float_cells("radiosity", st.radiosity[k], 3));
    image->GetCellData()->AddArray(float_cells("unshot", st.unshot[k], 3));
    std::vector<float> coverage(pm.coverage.size());
    for (size_t i = 0; i < coverage.size(); ++i)
      coverage[i] = static_cast<float>(pm.coverage[i] / (pm.texel_u * pm.texel_v));
    image->GetCellData()->AddArray(float_cells("coverage", coverage, 1));
    image->GetCellData()->AddArray(float_cells("displayed", out.display[k], 3));
    const std::string path = (dir / names[k]).string();
    vtkNew<internal::StreamXmlWriter<vtkXMLImageDataWriter>> writer;
    writer->SetInputData(image);
    writer->SetDataModeToBinary();
    writer->SetCompressorTypeToZLib();
    internal::write_xml_atomically(writer.Get(), path);
    written.push_back(path);
    nlohmann::json patches = nlohmann::json::array();
    for (int p : pm.patches) patches.push_back({{"index", p}, {"name", scene.patches[p].name}});
    doc["pixmaps"].push_back({{"file", names[k]},
                              {"width", pm.width},
                              {"height", pm.height},
                              {"material", scene.materials[pm.material].name},
                              {"patches", patches},
                              {"origin", vec(pm.origin)},
                              {"u", vec(pm.u)},
                              {"v", vec(pm.v)},
                              {"texel", {pm.texel_u, pm.texel_v}}});
  }
  doc["checksum"] = state_checksum(doc, st.radiosity, st.unshot);
  const std::string json_path = (dir / "state.json").string();
  write_json(json_path, doc);
  written.push_back(json_path);
  return written;
}

PixmapState read_pixmap_state(const std::string& dir) {
  const fs::path base = fs::path(dir) / "pixmaps";
  const std::string json_path = (base / "state.json").string();
  std::ifstream in(json_path);
  if (!in) throw IoError(json_path + ": cannot open (is " + dir + " the -o directory of a pixmap run?)");
  nlohmann::json doc;
  try {
    doc = parse_json_bounded(in, json_path);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(json_path + ": not valid JSON: " + e.what());
  }
  PixmapState st;
  st.source = json_path;
  auto bad = [&](const std::string& what) { return InputError(json_path + ": " + what); };
  try {
    if (doc.value("format", "") != "radmesh pixmap state") throw bad("not a radmesh pixmap state (\"format\")");
    if (doc.at("version").get<int>() != 3)
      throw bad("version " + doc.at("version").dump() +
                ", expected 3 (a state from another radmesh version: its texels and form factors differ; run again)");
    st.scene_fingerprint = doc.at("scene_fingerprint").get<std::string>();
    st.shots = doc.at("shots").get<long long>();
    const auto& o = doc.at("options");
    st.texel_size = o.at("texel_size").get<double>();
    st.max_texels = o.at("max_texels").get<long long>();
    st.hemicube_res = o.at("hemicube_res").get<int>();
    st.block = o.at("block").get<int>();
    for (int c = 0; c < 3; ++c) {
      st.power_absorbed[c] = doc.at("power_absorbed").at(static_cast<size_t>(c)).get<double>();
      st.power_escaped[c] = doc.at("power_escaped").at(static_cast<size_t>(c)).get<double>();
    }
    for (const auto& p : doc.at("pixmaps")) {
      const std::string file = p.at("file").get<std::string>();
      const int w = p.at("width").get<int>(), h = p.at("height").get<int>();
      if (w < 1 || h < 1) throw bad(file + ": size " + std::to_string(w) + " x " + std::to_string(h));
      const std::string path = (base / file).string();
      if (!fs::exists(path)) throw IoError(path + ": missing (listed in " + json_path + ")");
      vtkNew<vtkXMLImageDataReader> reader;
      reader->SetFileName(path.c_str());
      vtkNew<internal::VtkErrorCatcher> errors;
      reader->AddObserver(vtkCommand::ErrorEvent, errors);
      reader->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, errors);
      reader->Update();
      if (!errors->message.empty()) throw InputError(path + ": " + errors->message);
      vtkImageData* image = reader->GetOutput();
      int dims[3];
      image->GetDimensions(dims);
      if (dims[0] != w + 1 || dims[1] != h + 1)
        throw InputError(path + ": " + std::to_string(dims[0] - 1) + " x " + std::to_string(dims[1] - 1) +
                         " texels, the state says " + std::to_string(w) + " x " + std::to_string(h));
      auto array = [&](const char* name) {
        auto* a = vtkFloatArray::SafeDownCast(image->GetCellData()->GetArray(name));
        if (!a || a->GetNumberOfComponents() != 3 || a->GetNumberOfTuples() != static_cast<vtkIdType>(w) * h)
          throw InputError(path + ": no float RGB cell array \"" + std::string(name) + "\" of " +
                           std::to_string(static_cast<long long>(w) * h) + " texels");
        return std::vector<float>(a->GetPointer(0), a->GetPointer(0) + 3 * static_cast<size_t>(w) * h);
      };
      st.radiosity.push_back(array("radiosity"));
      st.unshot.push_back(array("unshot"));
      st.sizes.push_back({w, h});
    }
    // A state written without a checksum (radmesh 0.2) is taken as it is.
    if (doc.contains("checksum") && doc.at("checksum").get<std::string>() != state_checksum(doc, st.radiosity, st.unshot))
      throw bad("its contents do not match its checksum (" + doc.at("checksum").get<std::string>() +
                "): the state or one of its pixmap files was damaged, edited or swapped; run again without --resume");
  } catch (const nlohmann::json::exception& e) {
    throw bad(std::string("missing or wrong entry: ") + e.what());
  }
  return st;
}

std::vector<std::string> write_lightmaps(const std::string& out_dir, const Mesh& mesh, const PixmapOutput& out) {
  const PixmapSolver& solver = *out.solver;
  const PixmapLayout& L = solver.layout();
  const fs::path dir = fs::path(out_dir) / "lightmaps";
  std::vector<std::string> names;
  for (size_t k = 0; k < L.pixmaps.size(); ++k) names.push_back(pixmap_file(k, ".png"));
  internal::prepare_output_dir(dir.string(), R"(pixmap_[0-9]+\.png)", names);
  // One exposure for all: the 99th percentile of the reflected radiosity
  // (emitters aside) maps to white.
  std::vector<float> reflected;
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    const Pixmap& pm = L.pixmaps[k];
    if (pm.owner.empty()) continue;
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] >= 0)
        reflected.push_back(std::max({out.display[k][i * 3], out.display[k][i * 3 + 1], out.display[k][i * 3 + 2]}));
  }
  double white = 1.0;
  if (!reflected.empty()) {
    const size_t q = static_cast<size_t>(0.99 * static_cast<double>(reflected.size() - 1));
    std::nth_element(reflected.begin(), reflected.begin() + static_cast<long>(q), reflected.end());
    if (reflected[q] > 0.0f) white = reflected[q];
  }
  auto srgb = [](double c) {
    c = std::clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
  };
  std::vector<std::string> written;
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    const Pixmap& pm = L.pixmaps[k];
    const size_t n = static_cast<size_t>(pm.texels());
    std::vector<float> value(out.display[k]);
    std::vector<char> known(n);
    for (size_t i = 0; i < n; ++i) known[i] = pm.owner[i] >= 0;
    // Uncovered texels take the mean of their known neighbours, ring by ring.
    for (int pass = 0; pass < 4; ++pass) {
      std::vector<char> next(known);
      for (int j = 0; j < pm.height; ++j)
        for (int i = 0; i < pm.width; ++i) {
          const size_t idx = static_cast<size_t>(j) * pm.width + i;
          if (known[idx]) continue;
          float sum[3] = {0, 0, 0};
          int count = 0;
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int x = i + di, y = j + dj;
              if (x < 0 || y < 0 || x >= pm.width || y >= pm.height) continue;
              const size_t nb = static_cast<size_t>(y) * pm.width + x;
              if (!known[nb]) continue;
              for (int c = 0; c < 3; ++c) sum[c] += value[nb * 3 + c];
              ++count;
            }
          if (count == 0) continue;
          for (int c = 0; c < 3; ++c) value[idx * 3 + c] = sum[c] / static_cast<float>(count);
          next[idx] = 1;
        }
      known.swap(next);
    }
    vtkNew<vtkImageData> image;
    image->SetDimensions(pm.width, pm.height, 1);
    vtkNew<vtkUnsignedCharArray> rgb;
    rgb->SetNumberOfComponents(3);
    rgb->SetNumberOfTuples(static_cast<vtkIdType>(n));
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c)
        rgb->SetValue(static_cast<vtkIdType>(i * 3 + c),
                      static_cast<unsigned char>(std::lround(255.0 * srgb(value[i * 3 + c] / white))));
    image->GetPointData()->SetScalars(rgb);
    const std::string path = (dir / names[k]).string();
    vtkNew<vtkPNGWriter> writer;
    writer->SetInputData(image);
    writer->WriteToMemoryOn();
    internal::run_vtk_writer(writer.Get(), path);
    vtkUnsignedCharArray* bytes = writer->GetResult();
    write_file_atomically(path, [bytes](std::ostream& o) {
      o.write(reinterpret_cast<const char*>(bytes->GetPointer(0)), static_cast<std::streamsize>(bytes->GetNumberOfValues()));
    });
    written.push_back(path);
  }
  // The OBJ: the display mesh, (s, t) / size as vt, a material per pixmap.
  std::vector<std::array<double, 2>> uv;
  std::vector<int> vertex_pixmap;
  solver.display_uv(uv, vertex_pixmap);
  if (uv.size() != mesh.positions.size())
    throw IoError(out_dir + ": the mesh given is not the pixmap run's display mesh");
  const std::string mtl = (fs::path(out_dir) / "lightmapped.mtl").string();
  write_file_atomically(mtl, [&](std::ostream& o) {
    o << "# radmesh lightmaps: the radiosity baked into one texture per pixmap\n";
    for (size_t k = 0; k < L.pixmaps.size(); ++k)
      o << "newmtl lightmap_" << k << "\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nillum 0\nmap_Kd lightmaps/" << names[k] << "\n\n";
  });
  written.push_back(mtl);
  const std::string obj = (fs::path(out_dir) / "lightmapped.obj").string();
  write_file_atomically(obj, [&](std::ostream& o) {
    o.precision(17);
    o << "# radmesh lightmapped mesh: open it in a 3-D viewer; the light is in the textures\nmtllib lightmapped.mtl\n";
    for (const Vec3& p : mesh.positions) o << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const auto& t : uv) o << "vt " << t[0] << ' ' << t[1] << '\n';
    int current = -1;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const int k = vertex_pixmap[mesh.triangles[t][0]];
      if (k != current) {
        o << "g pixmap_" << k << "\nusemtl lightmap_" << k << '\n';
        current = k;
      }
      o << 'f';
      for (int c = 0; c < 3; ++c) o << ' ' << mesh.triangles[t][c] + 1 << '/' << mesh.triangles[t][c] + 1;
      o << '\n';
    }
  });
  written.push_back(obj);
  return written;
}

}  // namespace radmesh
