// Test scenes made by editing a bundled OBJ line by line. In a namespace of
// its own (not radmesh::test): test_cli.cpp names its runner `radmesh`.
#pragma once

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace test_files {

// Writes `dir`/scene.obj from the OBJ `src` + ".obj", each line (numbered
// from 1) through `edit`, which returns the text to write in its place (one
// or more lines); copies `src` + ".mtl" beside it under its own name, so
// that the OBJ's mtllib still finds it. Returns the new OBJ's path.
inline std::string write_edited_obj(const std::string& src, const std::filesystem::path& dir,
                                    const std::function<std::string(const std::string&, int)>& edit) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  fs::copy_file(src + ".mtl", dir / fs::path(src + ".mtl").filename(), fs::copy_options::overwrite_existing);
  std::ifstream in(src + ".obj");
  std::ofstream obj(dir / "scene.obj");
  int n = 0;
  for (std::string line; std::getline(in, line);) obj << edit(line, ++n) << '\n';
  return (dir / "scene.obj").string();
}

}  // namespace test_files
