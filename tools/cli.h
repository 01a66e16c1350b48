// stipple tools — small helpers shared by the subcommands of `stipple`.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace stipple::cli {

// Arguments after the subcommand name, consumed as they are recognised.
class Args {
 public:
  Args(int argc, char** argv, int first);
  bool flag(const char* name);                         // --name
  bool value(const char* name, std::string& out);      // --name VALUE or --name=VALUE
  std::vector<std::string> positionals();              // what is left, in order
  // Anything still unconsumed that looks like an option; empty if none.
  std::string unknown_option() const;
  bool bad() const { return !error_.empty(); }
  const std::string& error() const { return error_; }

 private:
  std::vector<std::string> args_;
  std::vector<bool> used_;
  std::string error_;
};

bool parse_uint(const std::string& s, unsigned long long max, unsigned long long& out);
bool parse_double(const std::string& s, double& out);
// "X,Y,Z": three finite numbers.
bool parse_vec3(const std::string& s, double out[3]);

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

// Human-readable byte count with thousands separators.
std::string with_commas(unsigned long long v);

int fail(const std::string& message);  // prints "stipple: <message>" to stderr, returns 1
void warn(const std::vector<std::string>& messages);  // prints "stipple: warning: <message>" for each

}  // namespace stipple::cli

namespace stipple {
int cmd_encode(int argc, char** argv);
int cmd_demo(int argc, char** argv);
int cmd_info(int argc, char** argv);
int cmd_sample(int argc, char** argv);
int cmd_metrics(int argc, char** argv);
int cmd_levels(int argc, char** argv);
int cmd_render(int argc, char** argv);
int cmd_ppn_table(int argc, char** argv);
int cmd_image_diff(int argc, char** argv);
int cmd_image_crc(int argc, char** argv);
}  // namespace stipple
