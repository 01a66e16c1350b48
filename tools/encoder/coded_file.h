// stipple host — writing `.spg` version 3: a version 2 file's records
// entropy-coded, each child against its parent (docs/format.md §5, "Coded
// records"; the reader is core/spg_coded.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace stipple {

// Sizes of one coded file, by part (what `stipple info` and the encoder's
// report print).
struct CodedFileReport {
  size_t records_bytes = 0;  // the version 2 records'
  size_t coded_bytes = 0;    // the coded section's: tables and batches with their lengths
  size_t tables_bytes = 0;
  size_t file_bytes = 0;     // the whole version 3 file
  uint32_t batches = 0;
  // The mean's bits a node, by depth (the root's 0): what the coder
  // spends on each level's positions — version 2 spends the layout's
  // position widths (32 bits by default) on every one.
  std::vector<double> mean_bits_by_depth;
  std::vector<uint32_t> nodes_by_depth;
};

// The version 3 file of the version 2 file data[0 .. size) into `out`; the
// tables counted over every record it codes. Checked before it returns:
// expanded, it gives back data's bytes exactly. `progress` (0..1) if given.
[[nodiscard]] bool write_coded_spg(const uint8_t* data, size_t size, std::vector<uint8_t>& out, CodedFileReport& report,
                                   std::string& error, const std::function<void(double)>& progress = {});

struct SpgView;

// The bytes a cut's records take entropy-coded as version 3 codes a file's
// nodes (ids ascending, each against the one before it; tables counted on
// these records, their bytes included, with the batches' lengths) — what
// `stipple rd` and `levels` give beside a cut's plain records, close to
// what a cold start's coded batch sends (docs/protocol.md, "Coded batches").
size_t coded_cut_bytes(const SpgView& view, const std::vector<uint32_t>& cut);

}  // namespace stipple
