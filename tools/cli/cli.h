// stipple tools — small helpers shared by the subcommands of `stipple`.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "tools/embedded/options.h"

namespace stipple {
struct ScanOptions;
}

namespace stipple::cli {

// A flat JSON object writer: {"key": value, ...}.
class Json {
 public:
  Json& num(const char* key, double v);
  Json& integer(const char* key, long long v);
  Json& str(const char* key, const std::string& v);
  Json& boolean(const char* key, bool v);
  Json& raw(const char* key, const std::string& json);
  std::string done() const { return "{" + body_ + "}"; }

 private:
  void key(const char* k);
  std::string body_;
};

int fail(const std::string& message);  // prints "stipple: <message>" to stderr, returns 1
// A pre-shared token from a file (serve --token, render --token): its
// bytes less trailing white space, 1..64 of them; false with a message
// naming the file.
bool read_token(const std::string& path, std::string& token, std::string& error);

// True (and `error` says so) when writing `output` would replace `input`:
// the same path or the same file by another name.
bool output_is_input(const std::string& input, const std::string& output, std::string& error);
void warn(const std::vector<std::string>& messages);

// Whether `output`'s name says what `writer` writes (`extension`, e.g.
// ".png", in the format `format`): a name that promises another image or
// model format (x.jpg for PNG bytes) is refused; any other extension gets a
// warning, printed here. An empty `output` passes.
bool check_output_name(const std::string& output, const char* extension, const char* format, std::string& error);

// The options of every verb that reads a scan (--columns), and their help.
extern const char kScanOptionsHelp[];
bool parse_scan_options(Args& args, ScanOptions& options, std::string& error);  // prints "stipple: warning: <message>" for each

}  // namespace stipple::cli

namespace stipple {
int cmd_encode(int argc, char** argv);
int cmd_encode_part(int argc, char** argv);
int cmd_demo(int argc, char** argv);
int cmd_info(int argc, char** argv);
int cmd_convert(int argc, char** argv);
int cmd_sample(int argc, char** argv);
int cmd_metrics(int argc, char** argv);
int cmd_levels(int argc, char** argv);
int cmd_render(int argc, char** argv);
int cmd_cut(int argc, char** argv);
int cmd_cut_table(int argc, char** argv);
int cmd_serve(int argc, char** argv);
int cmd_load(int argc, char** argv);
int cmd_ppn_table(int argc, char** argv);
int cmd_truth(int argc, char** argv);
int cmd_trade(int argc, char** argv);
int cmd_rd(int argc, char** argv);
int cmd_image_diff(int argc, char** argv);
int cmd_image_crc(int argc, char** argv);
}  // namespace stipple
