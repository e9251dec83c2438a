// The README's usage block says what `radmesh --help` says: for each
// subcommand, the same long flags, none missing and none extra.

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace {

// The long flags (--name) in `text`.
std::set<std::string> flags_in(const std::string& text) {
  std::set<std::string> out;
  const std::regex flag(R"((^|[\s\[|,])(--[a-z][a-z-]*))");
  for (std::sregex_iterator it(text.begin(), text.end(), flag), end; it != end; ++it) out.insert((*it)[2]);
  return out;
}

// Per subcommand, the README's usage lines (from "radmesh SUB" to the next).
std::map<std::string, std::string> readme_usage() {
  std::ifstream in(RADMESH_README);
  std::stringstream all;
  all << in.rdbuf();
  const std::string text = all.str();
  const size_t begin = text.find("<!-- usage begin -->"), end = text.find("<!-- usage end -->");
  EXPECT_NE(begin, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  std::map<std::string, std::string> out;
  std::string current;
  std::istringstream lines(text.substr(begin, end - begin));
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_search(line, m, std::regex(R"(^radmesh (\w+))"))) current = m[1];
    if (!current.empty()) out[current] += line + "\n";
  }
  return out;
}

// The option lines of `radmesh SUB --help`: where a flag is declared (the
// descriptions mention other flags).
std::string help_of(const std::string& sub) {
  FILE* p = popen((std::string(RADMESH_EXE) + " " + sub + " --help").c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && std::fgets(buf, sizeof buf, p)) {
    const std::string line = buf;
    if (std::regex_search(line, std::regex(R"(^  (-\w,)?--[a-z])"))) out += line;
  }
  if (p) pclose(p);
  return out;
}

}  // namespace

TEST(Usage, TheReadmeListsTheFlagsThatHelpLists) {
  const std::map<std::string, std::string> usage = readme_usage();
  for (const std::string sub : {"run", "mesh", "quality"}) {
    ASSERT_TRUE(usage.count(sub)) << "no 'radmesh " << sub << "' in the README's usage block";
    std::set<std::string> help = flags_in(help_of(sub));
    ASSERT_FALSE(help.empty()) << sub;
    const std::set<std::string> readme = flags_in(usage.at(sub));
    for (const std::string& f : help) EXPECT_TRUE(readme.count(f)) << "radmesh " << sub << " --help has " << f << ", the README not";
    for (const std::string& f : readme) EXPECT_TRUE(help.count(f)) << "the README has radmesh " << sub << " " << f << ", --help not";
  }
}
