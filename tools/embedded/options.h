// stipple tools — command-line options, shared by every program (stipple,
// stipple-handheld and those to come). Standard library only: builds for
// the handheld too.
#pragma once

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
  // "unknown option '--fram' (did you mean '--frames'?)" for unknown_option():
  // the nearest name this parser was asked about, where one is near.
  std::string unknown_option_message() const;
  bool bad() const { return !error_.empty(); }
  const std::string& error() const { return error_; }

 private:
  std::vector<std::string> args_;
  std::vector<bool> used_;
  std::vector<std::string> known_;  // every name flag() and value() were asked about
  std::string error_;
};

// The candidate nearest `word` by edit distance, where it is near enough to
// be what was meant (at most a third of its letters, and 3, apart); empty if
// none is.
std::string nearest(const std::string& word, const std::vector<std::string>& candidates);

// A count with thousands separators: "6,913" (every program's messages).
std::string with_commas(unsigned long long v);

bool parse_uint(const std::string& s, unsigned long long max, unsigned long long& out);
bool parse_double(const std::string& s, double& out);
// "X,Y,Z": three finite numbers.
bool parse_vec3(const std::string& s, double out[3]);

}  // namespace stipple::cli
