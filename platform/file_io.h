// stipple platform — whole-file reads and atomic writes with readable errors.
#pragma once

#include <cstdint>
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

}  // namespace stipple
