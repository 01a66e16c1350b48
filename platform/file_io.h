// stipple platform — whole-file reads and atomic writes with readable errors.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace stipple {

// Reads `path` into `out`. On failure returns false and sets `error` to
// "<path>: <reason>". Refuses files larger than `max_bytes`.
bool read_file(const std::string& path, std::vector<uint8_t>& out, std::string& error,
               uint64_t max_bytes = uint64_t{1} << 34);

// Writes `data` to `path` through a temporary file in the same folder, named
// for this process, and a rename: a failed or interrupted write never leaves
// a partial file, and two processes writing one path at once each leave a
// whole one. The file's bytes are flushed to the disk (fsync) before the
// rename and the folder's entry after it, so a power loss leaves the old
// file or the new one, never an empty one. A temporary file left by a
// writer that was killed (`PATH.partial.PID`, PID no longer running) is
// removed by the next write of PATH. The reason of a failure (a full disk:
// "No space left on device") is in the message. Refuses a directory as
// input ("is a directory").
bool write_file_atomic(const std::string& path, const std::vector<uint8_t>& data, std::string& error);

// A file mapped read-only into memory, for reading a file larger than
// memory front to back: release_before(offset) gives the pages before
// `offset` back (they are read again from the file if touched), so the
// pages a reader holds stay those it is reading. An empty file maps to no
// bytes. The error names the file.
class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();
  bool open(const std::string& path, std::string& error);  // closes what was open first
  void close();
  const uint8_t* data() const { return data_; }
  size_t size() const { return size_; }
  void release_before(size_t offset);

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0, released_ = 0;
};

// The same for a file written in pieces (a large .spg, streamed): open,
// write any number of times, then commit (flush, fsync, rename) — or
// abort, which the destructor does for a writer never committed, so an
// error or an early return leaves no partial file. A failed write is
// remembered: later writes do nothing and commit reports its reason.
class AtomicFileWriter {
 public:
  AtomicFileWriter() = default;
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();
  bool open(const std::string& path, std::string& error);
  bool write(const void* data, size_t size);  // false once a write has failed
  std::string failure() const;                // "<path>: write failed: <reason>" after a failed write
  bool commit(std::string& error);
  void abort();

 private:
  std::string path_, tmp_;
  std::FILE* file_ = nullptr;
  int errno_ = 0;
};

}  // namespace stipple
