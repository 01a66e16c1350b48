#include "platform/file_io.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace stipple {

bool read_file(const std::string& path, std::vector<uint8_t>& out, std::string& error, uint64_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    error = path + ": is a directory, not a file";
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = path + ": " + std::strerror(errno);
    return false;
  }
  out.clear();
  if (std::fseek(f, 0, SEEK_END) == 0) {
    const long size = std::ftell(f);
    if (size > 0 && static_cast<uint64_t>(size) > max_bytes) {
      std::fclose(f);
      error = path + ": file too large (" + std::to_string(size) + " bytes)";
      return false;
    }
    if (size > 0) out.reserve(static_cast<size_t>(size));
    std::fseek(f, 0, SEEK_SET);
  }
  uint8_t buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) {
    out.insert(out.end(), buffer, buffer + n);
    if (out.size() > max_bytes) {
      std::fclose(f);
      error = path + ": file too large";
      return false;
    }
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) {
    error = path + ": read error";
    return false;
  }
  return true;
}

bool write_file_atomic(const std::string& path, const std::vector<uint8_t>& data, std::string& error) {
  // A temporary name of this process's own beside the target, renamed over
  // it when complete: two runs writing one output at once each leave a
  // whole file, never a mixture, and a failed write leaves the old one.
  const std::string tmp = path + ".partial." + std::to_string(static_cast<long>(getpid()));
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    error = path + ": " + std::strerror(errno);
    return false;
  }
  const bool wrote = data.empty() || std::fwrite(data.data(), 1, data.size(), f) == data.size();
  const int write_errno = wrote ? 0 : errno;
  const bool closed = std::fclose(f) == 0;
  const int close_errno = closed ? 0 : errno;
  if (!wrote || !closed) {
    std::remove(tmp.c_str());
    const int why = write_errno ? write_errno : close_errno;
    error = path + ": write failed" + (why ? std::string(": ") + std::strerror(why) : std::string());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    error = path + ": " + std::strerror(errno);
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

}  // namespace stipple
