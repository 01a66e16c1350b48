#include "tools/cli.h"

#include <charconv>
#include <cmath>

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

std::string with_commas(unsigned long long v) {
  const std::string digits = std::to_string(v);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple: %s\n", message.c_str());
  return 1;
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

void warn(const std::vector<std::string>& messages) {
  for (const std::string& m : messages) std::fprintf(stderr, "stipple: warning: %s\n", m.c_str());
}

}  // namespace stipple::cli
