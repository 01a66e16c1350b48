// stipple tools — command-line options. See options.h.
#include "tools/embedded/options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace stipple::cli {

Args::Args(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i) args_.emplace_back(argv[i]);
  used_.assign(args_.size(), false);
}

bool Args::flag(const char* name) {
  known_.emplace_back(name);
  for (size_t i = 0; i < args_.size(); ++i)
    if (!used_[i] && args_[i] == name) return used_[i] = true;
  return false;
}

bool Args::value(const char* name, std::string& out) {
  known_.emplace_back(name);
  const std::string prefix = std::string(name) + "=";
  bool found = false;
  for (size_t i = 0; i < args_.size(); ++i) {
    if (used_[i]) continue;
    std::string v;
    if (args_[i] == name) {
      if (i + 1 >= args_.size()) {
        error_ = std::string(name) + " needs a value";
        return false;
      }
      // "-o --json": the value forgotten, the next option taken for it. No
      // value of ours starts with "--"; one that did could be given as
      // NAME=VALUE.
      if (args_[i + 1].rfind("--", 0) == 0 && args_[i + 1].size() > 2) {
        error_ = std::string(name) + " needs a value, but the next argument is the option '" + args_[i + 1] + "'";
        return false;
      }
      used_[i] = used_[i + 1] = true;
      v = args_[i + 1];
    } else if (args_[i].rfind(prefix, 0) == 0) {
      used_[i] = true;
      v = args_[i].substr(prefix.size());
    } else {
      continue;
    }
    if (found) {
      error_ = std::string(name) + " is given twice ('" + out + "' and '" + v + "'): give it once";
      return false;
    }
    found = true;
    out = v;
  }
  return found;
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

std::string Args::unknown_option_message() const {
  const std::string word = unknown_option();
  if (word.empty()) return {};
  if (word[0] != '-') return "unexpected argument '" + word + "'";
  const std::string name = word.substr(0, word.find('='));
  const std::string near = nearest(name, known_);
  return "unknown option '" + word + "'" + (near.empty() ? "" : " (did you mean '" + near + "'?)");
}

std::string nearest(const std::string& word, const std::vector<std::string>& candidates) {
  // Levenshtein distance, two rows.
  const auto distance = [](const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1), next(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
      next[0] = i;
      for (size_t j = 1; j <= b.size(); ++j)
        next[j] = std::min({row[j] + 1, next[j - 1] + 1, row[j - 1] + (a[i - 1] != b[j - 1])});
      row.swap(next);
    }
    return row[b.size()];
  };
  std::string best;
  size_t best_distance = 0;
  for (const std::string& c : candidates) {
    const size_t d = distance(word, c);
    if (d == 0 || d > 3 || 3 * d > std::max(word.size(), c.size())) continue;
    if (best.empty() || d < best_distance) best = c, best_distance = d;
  }
  return best;
}

std::string with_commas(unsigned long long v) {
  // Appended digit by digit (an insert here trips GCC 12's -O3 -Wrestrict false positive).
  const std::string digits = std::to_string(v);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
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
