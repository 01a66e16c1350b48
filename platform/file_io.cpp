#include "platform/file_io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <algorithm>
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

namespace {

// Removes PATH.partial.PID files whose writer is gone (killed mid-write):
// PID is all digits and no process has it.
void remove_stale_partials(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path target(path);
  const std::filesystem::path folder = target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
  const std::string prefix = target.filename().string() + ".partial.";
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid > 0 && kill(pid, 0) != 0 && errno == ESRCH) std::filesystem::remove(it->path(), ec);
  }
}

// fsync of the folder holding `path`: its new entry survives a power loss.
void sync_folder(const std::string& path) {
  const std::filesystem::path target(path);
  const std::string folder = target.has_parent_path() ? target.parent_path().string() : std::string(".");
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

}  // namespace

MappedFile::~MappedFile() { close(); }

void MappedFile::close() {
  if (data_) munmap(const_cast<uint8_t*>(data_), size_);
  data_ = nullptr;
  size_ = released_ = 0;
}

bool MappedFile::open(const std::string& path, std::string& error) {
  close();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return error = path + ": is a directory, not a file", false;
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return error = path + ": " + std::strerror(errno), false;
  struct stat st;
  if (fstat(fd, &st) != 0) {
    error = path + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  size_ = static_cast<size_t>(st.st_size);
  if (size_ > 0) {
    void* p = mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      error = path + ": " + std::strerror(errno);
      ::close(fd);
      size_ = 0;
      return false;
    }
    madvise(p, size_, MADV_SEQUENTIAL);
    data_ = static_cast<const uint8_t*>(p);
  }
  ::close(fd);
  return true;
}

void MappedFile::release_before(size_t offset) {
  static const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));  // readers call this for every point
  const size_t end = std::min(offset, size_) / page * page;
  if (!data_ || end <= released_ + (size_t{8} << 20)) return;  // in steps of 8 MB at least
  madvise(const_cast<uint8_t*>(data_) + released_, end - released_, MADV_DONTNEED);
  released_ = end;
}

AtomicFileWriter::~AtomicFileWriter() { abort(); }

bool AtomicFileWriter::open(const std::string& path, std::string& error) {
  abort();
  // A temporary name of this process's own beside the target, renamed over
  // it when complete: two runs writing one output at once each leave a
  // whole file, never a mixture, and a failed write leaves the old one.
  remove_stale_partials(path);
  path_ = path;
  tmp_ = path + ".partial." + std::to_string(static_cast<long>(getpid()));
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) return error = path + ": " + std::strerror(errno), false;
  errno_ = 0;
  return true;
}

bool AtomicFileWriter::write(const void* data, size_t size) {
  if (!file_) return false;
  if (errno_ == 0 && size > 0 && std::fwrite(data, 1, size, file_) != size) errno_ = errno ? errno : EIO;
  return errno_ == 0;
}

std::string AtomicFileWriter::failure() const {
  return path_ + ": write failed: " + std::strerror(errno_ ? errno_ : EIO);
}

bool AtomicFileWriter::commit(std::string& error) {
  if (!file_) return error = path_ + ": not open", false;
  int why = errno_;
  if (why == 0 && (std::fflush(file_) != 0 || ::fsync(fileno(file_)) != 0)) why = errno;  // on the disk
  if (std::fclose(file_) != 0 && why == 0) why = errno ? errno : EIO;
  file_ = nullptr;
  if (why != 0) {
    std::remove(tmp_.c_str());
    error = path_ + ": write failed: " + std::strerror(why);
    return false;
  }
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    error = path_ + ": " + std::strerror(errno);
    std::remove(tmp_.c_str());
    return false;
  }
  sync_folder(path_);
  return true;
}

void AtomicFileWriter::abort() {
  if (!file_) return;
  std::fclose(file_);
  file_ = nullptr;
  std::remove(tmp_.c_str());
}

bool write_file_atomic(const std::string& path, const std::vector<uint8_t>& data, std::string& error) {
  AtomicFileWriter out;
  if (!out.open(path, error)) return false;
  out.write(data.data(), data.size());
  return out.commit(error);
}

}  // namespace stipple
