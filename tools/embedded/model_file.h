// stipple — a .spg model as every program reads it: the file mapped
// read-only (or bytes handed over), validated once, its decoder, and the
// cut bounds — mapped from the cut table beside it (MODEL.spg.cut,
// core/cut_table.h) when that table is the model's, built in memory (36
// bytes a node) otherwise. `stipple serve`, the local viewers and
// `stipple-handheld` all open a model through it, so a model served by N
// processes, or drawn on a handheld, is one copy in the page cache and no
// process decodes the whole tree to start.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "core/view_cut.h"
#include "platform/file_io.h"

namespace stipple {

// Whether data[0 .. size) begins as a version 3 .spg (coded records,
// docs/format.md §5), which every reader expands before it reads.
bool spg_is_coded(const uint8_t* data, size_t size);
// A version 3 file in `file` replaced by the version 2 image it expands to
// (core/spg_coded.h); anything else left as it is, for its reader to judge.
// The error names the file as spg_error_message does.
bool expand_coded_spg(std::vector<uint8_t>& file, const std::string& name, std::string& error);
// The same from a version 3 file's bytes (spg_is_coded) into `image`.
bool expand_coded_spg(const uint8_t* data, size_t size, const std::string& name, std::vector<uint8_t>& image,
                      std::string& error);
// read_file, then expand_coded_spg: a .spg of any version as its readers take it.
bool read_spg_file(const std::string& path, std::vector<uint8_t>& out, std::string& error);

// Where a model's cut table is: beside it, MODEL.spg.cut.
std::string cut_table_path(const std::string& model_path);

class ModelFile {
 public:
  ModelFile() = default;
  ModelFile(const ModelFile&) = delete;
  ModelFile& operator=(const ModelFile&) = delete;

  // Maps `path` read-only (its pages are the page cache's: processes
  // reading one file share them) — a version 3 file is expanded into memory
  // instead — and validates it whole; maps its cut table
  // when that is the model's and made for `cones`, else builds the bounds
  // (nothing is written: `stipple encode` and `stipple cut-table` write tables).
  bool open(const std::string& path, const ConeRule& cones, std::string& error);
  // A whole .spg in memory (a scan encoded in memory, a test): bounds built.
  bool adopt(std::vector<uint8_t> file, const std::string& name, const ConeRule& cones, std::string& error);

  const std::string& name() const { return name_; }
  const SpgView& view() const { return view_; }
  const uint8_t* data() const { return data_; }
  size_t file_bytes() const { return size_; }
  // Opened from a version 3 file: the model is its expansion, held in
  // memory (file_bytes() its size), not a mapping of the file.
  bool expanded() const { return expanded_; }
  const NodeDecoder& decoder() const { return decoder_; }
  const CutBounds& bounds() const { return bounds_; }
  // What the tables take on the heap: the decoder's, and the bounds when
  // they were built rather than mapped.
  size_t table_bytes() const { return decoder_storage_.size() * 4 + bounds_storage_.size() * 8; }
  bool table_mapped() const { return table_.size() > 0; }
  // How the bounds came, for a log: "cut table MODEL.spg.cut mapped", or
  // why none was (missing, another model's, corrupt) and the bounds built.
  const std::string& table_note() const { return table_note_; }
  // A table there but refused (another model, corrupt): worth a warning.
  bool table_refused() const { return table_refused_; }

  // Writes the bounds as `path`'s cut table (atomically).
  bool write_table(const std::string& path, std::string& error) const;

 private:
  bool validate(std::string& error);
  bool build_bounds(std::string& error);
  MappedFile mapped_;
  MappedFile table_;
  std::vector<uint8_t> owned_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  std::string name_, table_note_;
  bool table_refused_ = false;
  bool expanded_ = false;
  ConeRule cones_;
  SpgView view_{};
  std::vector<uint32_t> decoder_storage_;
  NodeDecoder decoder_;
  std::vector<uint64_t> bounds_storage_;
  CutBounds bounds_;
};

// Makes the cut table of the model at `path` for `cones` unless the one
// beside it already is (*written says which); the error names the file.
bool make_cut_table(const std::string& path, const ConeRule& cones, std::string& error, bool* written = nullptr);

}  // namespace stipple
