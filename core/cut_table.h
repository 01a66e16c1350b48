// stipple core — the cut table file (MODEL.spg.cut): a model's per-node cut
// bounds (CutBounds, 36 bytes a node), made once — by `stipple encode`, or
// later by `stipple cut-table` — and then mapped read-only by every server
// process and local viewer of it, so that none decodes the whole tree at
// start-up and N processes share one copy in the page cache.
// The layout is in docs/format.md ("The cut table").
//
// A table names the model it was made from (its size, CRC-32 trailer and
// node count) and the cone rule its cones follow; one made for another
// model or rule is refused (kOtherModel, kOtherCones), and the caller makes
// the bounds itself. Its own CRC-32 covers the nodes, and what a cut's
// memory safety rests on is checked node by node (CutBounds::attach).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/spg_format.h"
#include "core/view_cut.h"

namespace stipple {

constexpr size_t kCutTableHeaderBytes = 64;
constexpr uint16_t kCutTableVersion = 1;

enum class CutTableError : uint8_t {
  kOk = 0,
  kTruncated,    // shorter than its header, or than its node count needs
  kBadMagic,     // not a cut table
  kBadVersion,   // a version this build does not read
  kOtherModel,   // made from another model (size, CRC-32 or node count differ)
  kOtherCones,   // made for another cone rule (--leaf-cone)
  kBadChecksum,  // the nodes' CRC-32 does not match
  kBadNode,      // a node fails CutBounds::attach's checks (node, field)
  kTrailingBytes,
};
const char* cut_table_error_text(CutTableError e);

// What identifies a model's file: its size and the CRC-32 it ends in
// (validated by spg_parse).
struct ModelTag {
  uint64_t bytes = 0;
  uint32_t crc = 0;
};
ModelTag model_tag(const uint8_t* file, size_t size);

// Bytes of a table for a model of `node_count` nodes: the header and 36
// bytes a node.
size_t cut_table_bytes(uint32_t node_count);
// The header of a table holding `bounds` (made by CutBounds::init for the
// tagged model with `cones`); the nodes follow it: bounds.table(), 36 bytes
// a node.
void cut_table_header(const ModelTag& tag, const ConeRule& cones, const CutBounds& bounds,
                      uint8_t out[kCutTableHeaderBytes]);

struct CutTableResult {
  CutTableError error = CutTableError::kOk;
  uint32_t node = 0;       // kBadNode: the node
  const char* field = "";  // kBadNode: the field
  bool ok() const { return error == CutTableError::kOk; }
};
// Checks `data[0 .. size)` as the cut table of the tagged model file, its
// `view` (node count, topology, leaf counts) and `cones`, and attaches
// `out` to its nodes (no copy: the data must outlive the bounds); refused,
// `out` is left unattached.
[[nodiscard]] CutTableResult cut_table_attach(const uint8_t* data, size_t size, const SpgView& view,
                                              const ModelTag& tag, const ConeRule& cones, CutBounds* out);

}  // namespace stipple
