#include "bench/scaling.h"

#include "bench/mesh_writers.h"
#include "bench/plot.h"
#include "io/writers/atomic_file.h"
#include "radmesh/scene_reader.h"
#include "radmesh/errors.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace radmesh::bench {

namespace fs = std::filesystem;

namespace {

using P3 = std::array<double, 3>;

// OBJ vertex lines, every digit of the doubles kept (OBJ is read in double).
void write_vertices(std::ostream& out, const std::vector<P3>& positions) {
  char buf[96];
  for (const P3& p : positions) {
    std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
    out << buf;
  }
}

// One OBJ being written: a vertex pool and objects of faces.
class ObjWriter {
public:
  int vertex(const P3& p) {
    positions_.push_back(p);
    return static_cast<int>(positions_.size());
  }
  void object(const std::string& name, const std::string& material) {
    faces_ << "o " << name << "\nusemtl " << material << '\n';
  }
  void face(std::initializer_list<int> ids) {
    faces_ << 'f';
    for (int i : ids) faces_ << ' ' << i;
    faces_ << '\n';
  }
  void quad(const P3& a, const P3& b, const P3& c, const P3& d) { face({vertex(a), vertex(b), vertex(c), vertex(d)}); }
  std::string write(const std::string& dir, const std::string& stem) const {
    fs::create_directories(dir);
    const fs::path obj = fs::path(dir) / (stem + ".obj");
    std::ofstream mtl(fs::path(dir) / (stem + ".mtl"));
    mtl << "# written by radmesh_bench --scaling\nnewmtl white\nKd 0.7 0.7 0.7\nnewmtl grey\nKd 0.5 0.5 0.5\n"
           "newmtl light\nKd 0 0 0\nKe 10 10 10\n";
    std::ofstream out(obj);
    out << "# written by radmesh_bench --scaling\nmtllib " << stem << ".mtl\n";
    write_vertices(out, positions_);
    out << faces_.str();
    if (!out || !mtl) throw IoError(obj.string() + ": cannot write the scene");
    return obj.string();
  }

private:
  std::vector<P3> positions_;
  std::ostringstream faces_;
};

constexpr double kX = 4.0, kY = 3.0, kZ = 4.0;  // the room

// Walls facing in, and a 1 x 1 light just below the ceiling facing down.
void room(ObjWriter& w) {
  w.object("floor", "white");
  w.quad({0, 0, 0}, {0, 0, kZ}, {kX, 0, kZ}, {kX, 0, 0});
  w.object("ceiling", "white");
  w.quad({0, kY, 0}, {kX, kY, 0}, {kX, kY, kZ}, {0, kY, kZ});
  w.object("walls", "white");
  w.quad({0, 0, 0}, {kX, 0, 0}, {kX, kY, 0}, {0, kY, 0});
  w.quad({0, 0, kZ}, {0, kY, kZ}, {kX, kY, kZ}, {kX, 0, kZ});
  w.quad({0, 0, 0}, {0, kY, 0}, {0, kY, kZ}, {0, 0, kZ});
  w.quad({kX, 0, 0}, {kX, 0, kZ}, {kX, kY, kZ}, {kX, kY, 0});
  const double h = kY - 0.01;
  w.object("light", "light");
  w.quad({1.5, h, 1.5}, {2.5, h, 1.5}, {2.5, h, 2.5}, {1.5, h, 2.5});
}

}  // namespace

std::string write_sphere_room(const std::string& dir, int level) {
  const test::Icosphere sphere = test::icosphere(level);
  ObjWriter w;
  room(w);
  const P3 centre = {2.0, 1.2, 2.0};
  const double radius = 0.8;
  std::vector<int> id(sphere.positions.size());
  w.object("sphere", "grey");
  for (size_t i = 0; i < id.size(); ++i) {
    const auto& v = sphere.positions[i];
    id[i] = w.vertex({centre[0] + radius * v[0], centre[1] + radius * v[1], centre[2] + radius * v[2]});
  }
  for (const auto& [a, b, c] : sphere.triangles)
    w.face({id[static_cast<size_t>(a)], id[static_cast<size_t>(b)], id[static_cast<size_t>(c)]});
  return w.write(dir, "sphere_" + std::to_string(level));
}

std::string write_boxes_room(const std::string& dir, int k) {
  ObjWriter w;
  room(w);
  const double margin = 0.5, cell = (kX - 2.0 * margin) / k, size = 0.5 * cell, height = 0.6 * cell;
  w.object("boxes", "grey");
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const double x0 = margin + (i + 0.25) * cell, z0 = margin + (j + 0.25) * cell;
      const double x1 = x0 + size, z1 = z0 + size, y = height;
      // Every face facing out: light that meets a face's back is lost.
      w.quad({x0, y, z0}, {x0, y, z1}, {x1, y, z1}, {x1, y, z0});  // top
      w.quad({x0, 0, z0}, {x0, y, z0}, {x1, y, z0}, {x1, 0, z0});  // -z
      w.quad({x0, 0, z1}, {x1, 0, z1}, {x1, y, z1}, {x0, y, z1});  // +z
      w.quad({x0, 0, z0}, {x0, 0, z1}, {x0, y, z1}, {x0, y, z0});  // -x
      w.quad({x1, 0, z0}, {x1, y, z0}, {x1, y, z1}, {x1, 0, z1});  // +x
    }
  return w.write(dir, "boxes_" + std::to_string(k));
}

namespace {

struct Run {
  std::string scene, clusters, method, status;
  double faces = 0.0, links = 0.0, wall = 0.0, peak_mb = 0.0, imbalance = 0.0;
  std::map<std::string, double> phases;  // summary.json's time_seconds
  std::map<std::string, double> objects;  // area-weighted mean radiosity (largest channel) per object name
  std::string field;
  double diff_off = -1.0, diff_matrix = -1.0;  // largest relative object-mean difference; -1 when not compared
};

// Runs `args` with stdout and stderr into `log`, killed after `limit`
// seconds. Returns (wall seconds, exit status or -1 when killed, peak KiB).
std::array<double, 3> run_process(const std::vector<std::string>& args, const std::string& log, double limit) {
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw IoError("fork failed");
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
    }
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage ru {};
  bool killed = false;
  for (;;) {
    const pid_t r = wait4(pid, &status, WNOHANG, &ru);
    if (r == pid) break;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!killed && t > limit) {
      kill(pid, SIGKILL);
      killed = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double code = killed ? -1.0 : (WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status));
  return {wall, code, static_cast<double>(ru.ru_maxrss)};
}

void read_summary(const std::string& path, Run& r) {
  std::ifstream in(path);
  const nlohmann::json s = nlohmann::json::parse(in);
  for (const auto& [k, v] : s.at("time_seconds").items()) r.phases[k] = v.get<double>();
  r.faces = s.at("counts").at("patches").get<double>();
  if (s.contains("solver") && s["solver"].contains("links")) r.links = s["solver"]["links"].get<double>();
  else r.links = s.at("counts").value("form_factors", 0.0);
  const auto& imb = s.at("energy").at("relative_imbalance");
  for (const auto& c : imb) r.imbalance = std::max(r.imbalance, std::abs(c.get<double>()));
  r.field = s.at("field").at("mode").get<std::string>();
  for (const auto& o : s.at("objects")) {
    double m = 0.0;
    for (const auto& c : o.at("mean_radiosity")) m = std::max(m, c.get<double>());
    r.objects[o.at("name").get<std::string>()] = m;
  }
}

double object_difference(const Run& a, const Run& b) {
  double worst = 0.0;
  for (const auto& [name, m] : a.objects) {
    const auto it = b.objects.find(name);
    if (it == b.objects.end() || !(it->second > 0.0)) continue;
    worst = std::max(worst, std::abs(m / it->second - 1.0));
  }
  return worst;
}

// The least-squares slope of log y against log x over points with x >= x_min.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y, double x_min) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (x[i] < x_min || !(y[i] > 0.0)) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    ++n;
  }
  if (n < 2) return std::nan("");
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace

std::string write_bunny_room(const std::string& dir, const std::string& data, int level) {
  // The bundled room as radmesh reads it (its transform applied, in double);
  // the bunny's faces are those named after its file.
  const fs::path room_json = fs::path(data) / "bunny" / "bunny_room.json";
  const Scene room = read_scene(room_json.string());
  std::vector<P3> v;
  std::vector<std::array<int, 3>> f;
  std::map<int, int> id;  // scene vertex -> v
  for (const Patch& p : room.patches) {
    if (p.name != "bunny") continue;
    if (p.outer.size() != 3 || !p.holes.empty()) throw InputError(room_json.string() + ": a bunny face is not a triangle");
    std::array<int, 3> t{};
    for (size_t k = 0; k < 3; ++k) {
      const auto [it, fresh] = id.try_emplace(p.outer[k], static_cast<int>(v.size()));
      if (fresh) {
        const Vec3& x = room.vertices[static_cast<size_t>(p.outer[k])];
        v.push_back({x.x, x.y, x.z});
      }
      t[k] = it->second;
    }
    f.push_back(t);
  }
  if (f.empty()) throw InputError(room_json.string() + ": no face named 'bunny'");
  // Each triangle into four by its edges' midpoints, `level` times: the same
  // surface, 4^level times the triangles (written in full; OBJ is read in
  // double).
  for (int l = 0; l < level; ++l) test::subdivide_at_midpoints(v, f, [](const P3& p) { return p; });
  fs::create_directories(dir);
  const std::string stem = "bunny_" + std::to_string(level);
  const fs::path obj = fs::path(dir) / (stem + ".obj");
  {
    std::ofstream out(obj);
    out << "# written by radmesh_bench --scaling: the bunny of " << room_json.string() << " cut into 4^" << level
        << " x its triangles\n";
    write_vertices(out, v);
    for (const auto& [a, b, c] : f) out << "f " << a + 1 << ' ' << b + 1 << ' ' << c + 1 << '\n';
    if (!out) throw IoError(obj.string() + ": cannot write the scene");
  }
  // The bundled JSON with the bunny's file replaced (its coordinates are
  // placed already: no transform) and the room's named where it lies.
  std::ifstream js(room_json);
  nlohmann::json scene = nlohmann::json::parse(js);
  for (auto& object : scene.at("objects")) {
    const std::string file = object.at("file").get<std::string>();
    if (fs::path(file).stem() == "bunny") {
      object["file"] = obj.string();
      object.erase("transform");
    } else {
      object["file"] = fs::absolute(room_json.parent_path() / file).string();
    }
  }
  const fs::path path = fs::path(dir) / (stem + ".json");
  std::ofstream out(path);
  out << scene.dump(1) << '\n';
  if (!out) throw IoError(path.string() + ": cannot write the scene");
  return path.string();
}

int scaling_benchmark(const ScalingOptions& o) {
  const std::string scene_dir = (fs::path(o.out_dir) / "scaling").string();
  fs::create_directories(scene_dir);
  // Scenes in order of size.
  std::vector<std::pair<double, std::string>> scenes;  // (approximate input faces, path)
  for (int level = 3; 20.0 * std::pow(4.0, level) <= o.max_triangles; ++level)
    scenes.emplace_back(20.0 * std::pow(4.0, level) + 7, write_sphere_room(scene_dir, level));
  for (int k = 8; 5.0 * k * k <= o.max_triangles; k *= 2) scenes.emplace_back(5.0 * k * k + 7, write_boxes_room(scene_dir, k));
  const std::string bunny = o.data + "/bunny/bunny_room.json";
  if (fs::exists(bunny)) {
    scenes.emplace_back(3684, bunny);
    // The scanned mesh cut finer: a real mesh's series, into the range where
    // its triangles fall below --min-area.
    for (int level = 1; 3674.0 * std::pow(4.0, level) + 10 <= o.max_triangles; ++level)
      scenes.emplace_back(3674.0 * std::pow(4.0, level) + 10, write_bunny_room(scene_dir, o.data, level));
  }
  std::stable_sort(scenes.begin(), scenes.end());

  std::vector<Run> runs;
  std::map<std::string, double> given_up;  // (family, configuration) -> faces where it ran out of time
  auto run_one = [&](const std::string& scene, double faces, const std::string& method, const std::string& clusters) {
    Run r;
    r.scene = fs::path(scene).stem().string();
    // A configuration that ran out of time is not tried on larger scenes of
    // the same family (sphere_5 after sphere_4; not the spheres after the bunny).
    const std::string config = r.scene.substr(0, r.scene.find('_')) + " " + method + "/" + clusters;
    r.clusters = clusters;
    r.method = method;
    r.faces = faces;
    if (given_up.count(config) && faces > given_up[config]) {
      r.status = "skipped";  // a smaller scene already ran past the time limit
      runs.push_back(r);
      return;
    }
    const std::string out = (fs::path(o.out_dir) / "scaling" / ("run_" + r.scene + "_" + method + "_" + clusters)).string();
    std::vector<std::string> args = {o.radmesh, "run", scene, "-o", out, "-q", "--no-png", "--method", method};
    if (method == "hierarchical") {
      args.push_back("--clusters");
      args.push_back(clusters);
    }
    fs::create_directories(out);
    const std::string log = out + ".log";
    std::fprintf(stderr, "scaling: %s %s/%s ...", r.scene.c_str(), method.c_str(), clusters.c_str());
    const auto [wall, code, peak] = run_process(args, log, o.time_limit);
    r.wall = wall;
    r.peak_mb = peak / 1024.0;
    if (code < 0) {
      r.status = "timeout";
      given_up[config] = faces;
    } else if (code != 0) {
      r.status = "failed (see " + log + ")";
    } else {
      r.status = "ok";
      read_summary(out + "/summary.json", r);
    }
    std::fprintf(stderr, " %s %.1f s, %.0f MB, %.3g links\n", r.status.c_str(), r.wall, r.peak_mb, r.links);
    runs.push_back(r);
  };
  for (const auto& [faces, scene] : scenes) {
    for (const std::string& mode : o.modes) run_one(scene, faces, "hierarchical", mode);
    if (faces <= o.matrix_up_to) run_one(scene, faces, "matrix", "-");
  }
  // Object means against off and the matrix method on the same scene.
  for (Run& r : runs) {
    if (r.status != "ok") continue;
    for (const Run& b : runs) {
      if (b.scene != r.scene || b.status != "ok") continue;
      if (b.method == "hierarchical" && b.clusters == "off" && &b != &r) r.diff_off = object_difference(r, b);
      if (b.method == "matrix" && &b != &r) r.diff_matrix = object_difference(r, b);
    }
  }
  const std::vector<std::string> phase_names = {"read", "mesh", "setup", "link", "solve", "direct", "gather", "write", "total"};
  std::ostringstream csv;
  csv << "scene,input_faces,method,clusters,status,links,wall_s";
  for (const std::string& p : phase_names) csv << ',' << p << "_s";
  csv << ",peak_mb,energy_imbalance,field,object_diff_vs_off,object_diff_vs_matrix\n";
  for (const Run& r : runs) {
    csv << r.scene << ',' << r.faces << ',' << r.method << ',' << r.clusters << ',' << r.status << ',' << r.links << ','
        << r.wall;
    for (const std::string& p : phase_names) {
      const auto it = r.phases.find(p);
      csv << ',' << (it == r.phases.end() ? 0.0 : it->second);
    }
    csv << ',' << r.peak_mb << ',' << r.imbalance << ',' << r.field << ',' << r.diff_off << ',' << r.diff_matrix << '\n';
  }
  const std::string path = (fs::path(o.out_dir) / "scaling.csv").string();
  write_file_atomically(path, [&](std::ostream& out) { out << csv.str(); });
  std::printf("%s\n", path.c_str());
  // Slopes and plots: one series per family of scenes (the sphere rooms,
  // the box fields, the bunny cut finer) and mode.
  const std::vector<std::pair<std::string, std::string>> families = {
      {"sphere", "sphere room"}, {"boxes", "box field"}, {"bunny", "bunny room"}};
  std::vector<Series> time_series, link_series;
  for (const std::string& mode : o.modes)
    for (const auto& [prefix, label] : families) {
      Series t{label + ", clusters " + mode, {}, {}}, l{label + ", clusters " + mode, {}, {}};
      for (const Run& r : runs)
        if (r.status == "ok" && r.method == "hierarchical" && r.clusters == mode &&
            r.scene.substr(0, r.scene.find('_')) == prefix) {
          t.x.push_back(r.faces);
          t.y.push_back(r.wall);
          l.x.push_back(r.faces);
          l.y.push_back(r.links);
        }
      if (t.x.empty()) continue;
      // From 10^4 faces where two runs are there, else over every run of
      // the family (said so: small scenes have the O(1) costs in them).
      const long from = std::count_if(t.x.begin(), t.x.end(), [](double f) { return f >= 1e4; });
      const double x_min = from >= 2 ? 1e4 : 0.0;
      const auto [lo, hi] = std::minmax_element(t.x.begin(), t.x.end());
      if (t.x.size() < 2)
        std::printf("clusters %s, %s: one run (%.0f faces), no slope\n", mode.c_str(), label.c_str(), *lo);
      else
        std::printf("clusters %s, %s: log-log slope %s (%ld runs up to %.0f faces): links %.3f, wall time %.3f\n",
                    mode.c_str(), label.c_str(), from >= 2 ? "from 10^4 faces" : "over every run, fewer than two from 10^4",
                    from >= 2 ? from : static_cast<long>(t.x.size()), *hi, loglog_slope(l.x, l.y, x_min),
                    loglog_slope(t.x, t.y, x_min));
      time_series.push_back(t);
      link_series.push_back(l);
    }
  std::string why;
  const std::string tpng = (fs::path(o.out_dir) / "scaling_time.png").string();
  const std::string lpng = (fs::path(o.out_dir) / "scaling_links.png").string();
  if (plot_error_vs_time(tpng, "radmesh: wall time against input faces", "wall time [s]", time_series, &why,
                         "input faces") &&
      plot_error_vs_time(lpng, "radmesh: links against input faces", "links", link_series, &why, "input faces")) {
    std::printf("%s\n%s\n", tpng.c_str(), lpng.c_str());
  } else {
    std::fprintf(stderr, "plots skipped: %s\n", why.c_str());
  }
  return 0;
}

}  // namespace radmesh::bench
