// stipple tools — command-line options. See options.h.
#include "tools/embedded/options.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

namespace stipple::cli {

Args::Args(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i) args_.emplace_back(argv[i]);
  used_.assign(args_.size(), false);
}

bool Args::flag(const char* name) {
  for (size_t i = 0; i < args_.size(); ++i)
    if (!used_[i] && args_[i] == name) return used_[i] = true;
  return false;
}

bool Args::value(const char* name, std::string& out) {
  const std::string prefix = std::string(name) + "=";
  for (size_t i = 0; i < args_.size(); ++i) {
    if (used_[i]) continue;
    if (args_[i] == name) {
      if (i + 1 >= args_.size()) {
        error_ = std::string(name) + " needs a value";
        return false;
      }
      used_[i] = used_[i + 1] = true;
      out = args_[i + 1];
      return true;
    }
    if (args_[i].rfind(prefix, 0) == 0) {
      used_[i] = true;
      out = args_[i].substr(prefix.size());
      return true;
    }
  }
  return false;
}

std::vector<std::string> Args::positionals() {
  std::vector<std::string> out;
  for (size_t i = 0; i < args_.size(); ++i)
    if (!used_[i] && (args_[i].empty() || args_[i][0] != '-' || args_[i] == "-")) {
      used_[i] = true;
      out.push_back(args_[i]);
    }
  return out;
}

std::string Args::unknown_option() const {
  for (size_t i = 0; i < args_.size(); ++i)
    if (!used_[i]) return args_[i];
  return {};
}

bool parse_uint(const std::string& s, unsigned long long max, unsigned long long& out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && out <= max;
}

bool parse_double(const std::string& s, double& out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(out);
}

bool parse_vec3(const std::string& s, double out[3]) {
  size_t start = 0;
  for (int k = 0; k < 3; ++k) {
    const size_t comma = k < 2 ? s.find(',', start) : std::string::npos;
    if (k < 2 && comma == std::string::npos) return false;
    if (!parse_double(s.substr(start, comma == std::string::npos ? std::string::npos : comma - start), out[k]) ||
        !std::isfinite(out[k]))
      return false;
    start = comma + 1;
  }
  return true;
}

}  // namespace stipple::cli
