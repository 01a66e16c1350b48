#include "tools/cli/cli.h"

#include <charconv>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "core/protocol.h"
#include "platform/file_io.h"
#include "tools/scan/ply_io.h"

namespace stipple::cli {

void Json::key(const char* k) {
  if (!body_.empty()) body_ += ", ";
  body_ += "\"";
  body_ += k;
  body_ += "\": ";
}
Json& Json::num(const char* k, double v) {
  key(k);
  if (!std::isfinite(v)) {
    body_ += "null";
    return *this;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  body_ += buf;
  return *this;
}
Json& Json::integer(const char* k, long long v) {
  key(k);
  body_ += std::to_string(v);
  return *this;
}
Json& Json::str(const char* k, const std::string& v) {
  key(k);
  body_ += "\"";
  for (char c : v) {
    if (c == '"' || c == '\\') body_ += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      body_ += buf;
      continue;
    }
    body_ += c;
  }
  body_ += "\"";
  return *this;
}
Json& Json::boolean(const char* k, bool v) {
  key(k);
  body_ += v ? "true" : "false";
  return *this;
}
Json& Json::raw(const char* k, const std::string& json) {
  key(k);
  body_ += json;
  return *this;
}

bool output_is_input(const std::string& input, const std::string& output, std::string& error) {
  std::error_code ec;
  if (input == output || (std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec))) {
    error = output + ": the output is the input file; writing it would destroy " + input + " (choose another -o)";
    return true;
  }
  return false;
}

const char kScanOptionsHelp[] =
    "scan options (PLY, PCD and LAS headers name their fields; text is told by\n"
    "its column count and values, with a warning where that is a guess):\n"
    "  --columns LIST        a text scan's columns, in order: x y z (required),\n"
    "                        nx ny nz, r g b (0..255), - to skip one; for example\n"
    "                        --columns x,y,z,-,r,g,b for x y z intensity r g b\n"
    "  --color-by rgb|intensity|classification\n"
    "                        a LAS scan's colour: its RGB (default), its intensity\n"
    "                        as grey, or its classification (ground brown, vegetation\n"
    "                        green, buildings red, water blue: `stipple render\n"
    "                        --legend classification` shows the key)\n";

bool parse_scan_options(Args& args, ScanOptions& options, std::string& error) {
  std::string spec;
  if (args.value("--columns", spec) && !parse_text_columns(spec, options.columns, error)) return false;
  if (std::string by; args.value("--color-by", by)) {
    if (by == "rgb") options.color_by = LasColor::kRgb;
    else if (by == "intensity") options.color_by = LasColor::kIntensity;
    else if (by == "classification") options.color_by = LasColor::kClassification;
    else return error = "--color-by: expected rgb, intensity or classification, got '" + by + "'", false;
  }
  return true;
}

bool check_output_name(const std::string& output, const char* extension, const char* format, std::string& error) {
  if (output.empty()) return true;
  std::string ext = std::filesystem::path(output).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == extension) return true;
  // Extensions that name a format of their own: bytes of another format
  // under them would be misread by every program that opens them.
  static const char* const kOtherFormats[] = {".png", ".jpg", ".jpeg", ".bmp", ".gif", ".tif", ".tiff", ".webp",
                                              ".ppm", ".pgm", ".spg", ".ply", ".pcd", ".las", ".laz", ".e57",
                                              ".xyz", ".pts", ".obj", ".csv", ".txt", ".json"};
  for (const char* other : kOtherFormats)
    if (ext == other)
      return error = output + ": this writes " + format + ", not " + ext.substr(1) + " (name the output " + extension + ")",
             false;
  warn({output + ": written as " + format + (ext.empty() ? std::string(" (the name has no extension)") : ", whatever '" + ext + "' says") +
        "; " + extension + " is its usual name"});
  return true;
}

bool read_token(const std::string& path, std::string& token, std::string& error) {
  std::vector<uint8_t> bytes;
  if (!read_file(path, bytes, error)) return false;
  token.assign(bytes.begin(), bytes.end());
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ' || token.back() == '\t'))
    token.pop_back();
  if (token.empty()) return error = path + ": the token file is empty", false;
  if (token.size() > kMaxTokenBytes)
    return error = path + ": a token of " + std::to_string(token.size()) + " bytes; at most " +
                   std::to_string(kMaxTokenBytes) + " are carried",
           false;
  return true;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple: %s\n", message.c_str());
  return 1;
}

void warn(const std::vector<std::string>& messages) {
  for (const std::string& m : messages) std::fprintf(stderr, "stipple: warning: %s\n", m.c_str());
}

}  // namespace stipple::cli
