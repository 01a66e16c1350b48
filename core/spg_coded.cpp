// stipple core — `.spg` version 3 read by expansion. See spg_coded.h and
// docs/format.md §5.
#include "core/spg_coded.h"

#include "core/node_coding.h"
#include "core/spg_writer.h"

namespace stipple {

size_t spg_expanded_bytes(const SpgView& view, const SpgCodedParts& parts) {
  return parts.records_offset + size_t{view.header.node_count} * view.record_bytes + 4;
}

SpgResult spg_expand(const uint8_t* data, const SpgView& view, const SpgCodedParts& parts, uint8_t* image,
                     uint8_t* points) {
  const SpgHeader& h = view.header;
  const size_t bytes = spg_expanded_bytes(view, parts);
  const size_t tables_at = parts.records_offset + 4;
  for (size_t i = 0; i < parts.records_offset; ++i) image[i] = data[i];
  store_u16le(image + spg_offset::kVersion, kSpgVersion);
  CodeTables tables;
  if (!parse_code_tables(parts.tables, parts.tables_bytes, spg_coded_table_header(h), &tables))
    return SpgResult{SpgError::kBadCoded, tables_at, 0};
  spg_node_points(view, points, 1);
  uint8_t* const records = image + parts.records_offset;
  const auto record = [&](uint32_t id) { return records + size_t{id} * view.record_bytes; };
  const auto fields = [&](uint32_t id) { return unpack_record(h.layout, record(id)); };
  uint32_t next = 0;  // the next node to decode
  const uint8_t* at = parts.batches + 4;
  for (uint32_t b = 0; b < parts.batch_count; ++b) {
    const size_t length = load_u32le(at);
    const SpgResult bad{SpgError::kBadCoded, static_cast<size_t>(at - data), 0};
    CodedBatchReader in;
    if (!in.init(tables, at + 4, length, h.node_count)) return bad;
    at += 4 + length;
    for (CodedBatchReader::Entry e; in.done() < in.count();) {
      if (!in.next(&e) || e.id != next || e.points != points[e.id]) return bad;
      if (e.kind == 0) {
        NodeFields f{};
        // Against the node before it; the root against zeros. The context
        // is the coder's rule (node_coding.h): reference + 1 == id, the
        // root's "none" (0xFFFFFFFF) included.
        if (!in.node(e.id > 0 ? fields(e.id - 1) : NodeFields{}, true, &f)) return bad;
        pack_record(h.layout, f, record(e.id));
        next = e.id + 1;
        continue;
      }
      NodeFields first{}, second{};
      uint8_t second_points = 0;
      if (e.parent >= e.id || !in.split(fields(e.parent), points[e.parent], &first, &second, &second_points) ||
          second_points != points[e.id + 1])
        return bad;
      pack_record(h.layout, first, record(e.id));
      pack_record(h.layout, second, record(e.id + 1));
      next = e.id + 2;
    }
    if (!in.finish()) return bad;
  }
  if (next != h.node_count) return SpgResult{SpgError::kBadCoded, parts.records_offset, 0};
  store_u32le(image + bytes - 4, crc32(image, bytes - 4));
  SpgView expanded;
  return spg_parse(image, bytes, &expanded);
}

}  // namespace stipple
