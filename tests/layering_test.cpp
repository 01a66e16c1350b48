// The dependency direction tools -> platform -> raster -> core, and core's
// rules: no OS, SDL, GL, libpng or Eigen header, no exceptions, no iostream.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "test_util.h"

namespace stipple {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> includes_of(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  const std::regex inc(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  std::string line;
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_search(line, m, inc)) out.push_back(m[1]);
  return out;
}

std::vector<fs::path> sources(const std::string& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(test::source_path(folder)))
    if (e.path().extension() == ".h" || e.path().extension() == ".cpp") out.push_back(e.path());
  return out;
}

TEST(Layering, DependenciesPointDownward) {
  const std::map<std::string, std::vector<std::string>> allowed = {
      {"core", {"core/"}}, {"raster", {"core/", "raster/"}}, {"platform", {"core/", "raster/", "platform/"}}};
  const std::vector<std::string> project = {"core/", "raster/", "platform/", "tools/", "tests/"};
  for (const auto& [folder, ok] : allowed) {
    for (const fs::path& file : sources(folder)) {
      for (const std::string& inc : includes_of(file)) {
        for (const std::string& p : project) {
          if (inc.rfind(p, 0) != 0) continue;
          EXPECT_TRUE(std::find(ok.begin(), ok.end(), p) != ok.end())
              << file << " includes " << inc << ": " << folder << "/ may not depend on " << p;
        }
      }
    }
  }
}

TEST(Layering, CoreAndRasterUseStandardHeadersOnly) {
  const std::regex forbidden(
      R"(^(SDL|GL/|GLES|EGL|png\.h|Eigen|unistd|sys/|windows|iostream|fstream|sstream|thread|mutex|stdexcept|exception))");
  for (const std::string folder : {"core", "raster"}) {
    for (const fs::path& file : sources(folder)) {
      for (const std::string& inc : includes_of(file))
        EXPECT_FALSE(std::regex_search(inc, forbidden)) << file << " includes " << inc;
      std::ifstream in(file);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      EXPECT_EQ(text.find("throw "), std::string::npos) << file << " throws";
      EXPECT_EQ(std::regex_search(text, std::regex(R"(\b(float|double)\b)")), false)
          << file << " uses floating point";
    }
  }
}

}  // namespace
}  // namespace stipple
