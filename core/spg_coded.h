// stipple core — reading `.spg` version 3, whose records are entropy-coded
// (docs/format.md §5, "Coded records"), by expanding it into the version 2
// file it stands for, byte for byte.
//
// Version 3 stores each node's record against its parent's — a split of
// the coded batches' (core/node_coding.h): the first child's fields as
// differences from the parent's, the second's mean from the count-weighted
// mix of the two (TOG05), the rest against its sibling — so the mean costs
// what the child's place in its parent's extent needs, fewer bits the
// deeper the node, and every field what its statistics over the whole tree
// say. It is a format to store and carry: every reader expands it once,
// when it opens the file, and reads the image as any version 2 file.
//
//   SpgView view; SpgCodedParts parts;
//   spg_parse_coded(data, size, &view, &parts);               // every check but the records'
//   image.resize(spg_expanded_bytes(view, parts)); scratch.resize(view.header.node_count);
//   spg_expand(data, view, parts, image.data(), scratch.data());  // then spg_parse(image)
//
// Nothing is allocated or thrown and no floating point is used; the code
// tables (18 KB) live on the stack while the file is expanded.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/spg_format.h"

namespace stipple {

// Nodes a batch of a version 3 file holds at most (the writer's choice; the
// reader takes any split of the ids into batches, in order).
inline constexpr uint32_t kSpgCodedBatchNodes = 65536;

// The header a version 3 file's code tables are written and read for: the
// file's, as version 1 — its class tables are stored as they are, so the
// tables carry no class models.
inline SpgHeader spg_coded_table_header(SpgHeader h) {
  h.version = 1;
  return h;
}

// The version 2 image's bytes.
size_t spg_expanded_bytes(const SpgView& view, const SpgCodedParts& parts);

// Decodes a version 3 file that spg_parse_coded validated into the version
// 2 image `image` (spg_expanded_bytes) with `points` (node_count bytes) to
// work in, and validates the image as spg_parse does. The batches must
// hold every node once, in order, each split after its parent, with the
// points bytes the leaf counts give; tables that do not parse, or a batch
// that decodes otherwise, is cut short or runs on, is kBadCoded at its
// offset in the file. Other errors are the image's (offsets in it).
[[nodiscard]] SpgResult spg_expand(const uint8_t* data, const SpgView& view, const SpgCodedParts& parts, uint8_t* image,
                                   uint8_t* points);

}  // namespace stipple
