// The dependency direction tools -> platform -> raster -> core, and core's
// rules: no OS, SDL, GL, libpng or Eigen header, no exceptions, no iostream.
// The rooms of DESIGN.md: no tools/ library includes a program's folder; the
// portable suite includes only core, raster and its own fixtures; the GPU
// renderer (platform/gl/) never includes raster/; what the handheld builds
// (tools/embedded/) uses no host library.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "test_util.h"

namespace stipple {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> includes_of(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    const size_t hash = line.find_first_not_of(" \t");
    if (hash == std::string::npos || line[hash] != '#') continue;
    const size_t word = line.find_first_not_of(" \t", hash + 1);
    if (word == std::string::npos || line.compare(word, 7, "include") != 0) continue;
    const size_t open = line.find_first_of("<\"", word + 7);
    const size_t close = open == std::string::npos ? open : line.find_first_of(">\"", open + 1);
    if (close != std::string::npos) out.push_back(line.substr(open + 1, close - open - 1));
  }
  return out;
}

bool is_word_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// True if `word` occurs in `text` as a whole identifier.
bool has_word(const std::string& text, const std::string& word) {
  for (size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
    const bool start = at == 0 || !is_word_char(text[at - 1]);
    const bool end = at + word.size() >= text.size() || !is_word_char(text[at + word.size()]);
    if (start && end) return true;
  }
  return false;
}

std::vector<fs::path> sources(const std::string& folder) {
  std::vector<fs::path> out;
  if (!fs::exists(test::source_path(folder))) return out;  // a room not built yet
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
  const char* forbidden[] = {"SDL", "GL/", "GLES", "EGL", "png.h", "Eigen", "unistd", "sys/", "windows",
                             "iostream", "fstream", "sstream", "thread", "mutex", "stdexcept", "exception"};
  for (const std::string folder : {"core", "raster"}) {
    for (const fs::path& file : sources(folder)) {
      for (const std::string& inc : includes_of(file))
        for (const char* bad : forbidden) EXPECT_NE(inc.rfind(bad, 0), 0u) << file << " includes " << inc;
      std::ifstream in(file);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      EXPECT_EQ(text.find("throw "), std::string::npos) << file << " throws";
      EXPECT_FALSE(has_word(text, "float")) << file << " uses floating point";
      EXPECT_FALSE(has_word(text, "double")) << file << " uses floating point";
    }
  }
}

// tools/: libraries by concern, and program folders (a main each). A
// library may not reach into a program.
const std::vector<std::string> kProgramFolders = {"tools/cli/", "tools/handheld/", "tools/emulator/", "tools/gl/",
                                                  "tools/bench/"};

TEST(Layering, NoToolsLibraryIncludesAProgram) {
  size_t checked = 0;
  for (const auto& e : fs::directory_iterator(test::source_path("tools"))) {
    if (!e.is_directory()) continue;
    const std::string folder = "tools/" + e.path().filename().string() + "/";
    if (std::find(kProgramFolders.begin(), kProgramFolders.end(), folder) != kProgramFolders.end()) continue;
    for (const fs::path& file : sources(folder.substr(0, folder.size() - 1))) {
      ++checked;
      for (const std::string& inc : includes_of(file))
        for (const std::string& program : kProgramFolders)
          EXPECT_NE(inc.rfind(program, 0), 0u) << file << " includes " << inc << ": a library may not use a program's folder";
    }
  }
  EXPECT_GT(checked, 10u);
}

TEST(Layering, PortableSuiteSeesOnlyCoreRasterAndFixtures) {
  const std::vector<std::string> ok = {"core/", "raster/", "tests/portable/", "gtest/"};
  const std::vector<fs::path> files = sources("tests/portable");
  ASSERT_FALSE(files.empty());
  for (const fs::path& file : files)
    for (const std::string& inc : includes_of(file)) {
      if (inc.find('/') == std::string::npos) continue;  // <vector>, <cstdint>: the standard library
      const bool allowed = std::any_of(ok.begin(), ok.end(), [&](const std::string& p) { return inc.rfind(p, 0) == 0; });
      EXPECT_TRUE(allowed) << file << " includes " << inc << ": the portable suite runs on every target";
    }
}

TEST(Layering, GpuClientNeverIncludesRaster) {
  for (const fs::path& file : sources("platform/gl"))
    for (const std::string& inc : includes_of(file))
      EXPECT_NE(inc.rfind("raster/", 0), 0u) << file << " includes " << inc << ": the GL client uses core's node cache";
}

TEST(Layering, EmbeddedDefaultUsesNoHostLibrary) {
  const char* host[] = {"Eigen",          "png.h",        "platform/png_io.h", "tools/host/", "tools/encoder/",
                        "tools/scan/",    "tools/server/", "tools/reference/", "SDL",         "GL/",
                        "EGL"};
  const std::vector<fs::path> files = sources("tools/embedded");
  ASSERT_FALSE(files.empty());
  for (const fs::path& file : files)
    for (const std::string& inc : includes_of(file))
      for (const char* bad : host) EXPECT_NE(inc.rfind(bad, 0), 0u) << file << " includes " << inc << ": it builds for the handheld";
}

}  // namespace
}  // namespace stipple
