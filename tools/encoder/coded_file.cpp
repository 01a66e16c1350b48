// stipple host — writing `.spg` version 3. See coded_file.h.
#include "tools/encoder/coded_file.h"

#include <algorithm>
#include <memory>

#include "core/node_coding.h"
#include "core/protocol.h"
#include "core/spg_coded.h"
#include "core/spg_format.h"
#include "core/spg_writer.h"

namespace stipple {
namespace {

// Calls f(unit, size) for the units of the file's one coded sequence, in id
// order: the root as a node, then each node with two children as a split
// of them (binary trees: every other node), or — octrees — every node after
// the root as a node against the one before it.
template <typename F>
void for_each_unit(const SpgView& view, const uint8_t* points, F&& f) {
  const SpgHeader& h = view.header;
  const auto fields = [&](uint32_t id) { return unpack_record(h.layout, view.records + size_t{id} * view.record_bytes); };
  CodedEntry unit[2];
  unit[0] = CodedEntry{};
  unit[0].fields = fields(0);
  unit[0].points = points[0];
  f(unit, 1u);
  if (h.tree_arity != 2) {
    for (uint32_t id = 1; id < h.node_count; ++id) {
      unit[0] = CodedEntry{};
      unit[0].id = id;
      unit[0].points = points[id];
      unit[0].fields = fields(id);
      unit[0].reference_id = id - 1;
      unit[0].reference = fields(id - 1);
      f(unit, 1u);
    }
    return;
  }
  uint32_t child = 1;
  for (uint32_t id = 0; id < h.node_count; ++id) {
    if (spg_child_count(view, id) != 2) continue;
    unit[0] = CodedEntry{};
    unit[0].id = child;
    unit[0].kind = 1;
    unit[0].points = points[child];
    unit[0].fields = fields(child);
    unit[0].reference_id = id;
    unit[0].reference_points = points[id];
    unit[0].reference = fields(id);
    unit[1] = CodedEntry{};
    unit[1].id = child + 1;
    unit[1].kind = 2;
    unit[1].points = points[child + 1];
    unit[1].fields = fields(child + 1);
    f(unit, 2u);
    child += 2;
  }
}

// Calls f(batch) for the file's units in batches of at most
// kSpgCodedBatchNodes nodes, in order (a split is never cut).
template <typename F>
void for_each_batch(const SpgView& view, const uint8_t* points, F&& f) {
  std::vector<CodedEntry> batch;
  for_each_unit(view, points, [&](const CodedEntry* unit, uint32_t k) {
    if (batch.size() + k > kSpgCodedBatchNodes) {
      f(batch);
      batch.clear();
    }
    batch.insert(batch.end(), unit, unit + k);
  });
  if (!batch.empty()) f(batch);
}

// Tables counted on every entry of `batches` (a callable that gives them
// batch by batch), as a version 3 file's are (unseen models at the floor).
template <typename Batches>
CodeTables counted_tables(const SpgView& view, Batches&& batches) {
  auto tally = std::make_unique<CodeTally>();  // 62 KB
  tally->layout = view.header.layout;
  batches([&](const std::vector<CodedEntry>& b) { tally->batch(b.data(), static_cast<uint32_t>(b.size())); });
  CodeTables tables;
  tally->tables(view, spg_coded_table_header(view.header), kProtocolVersion, &tables, true);
  return tables;
}

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  uint8_t b[4];
  store_u32le(b, v);
  out.insert(out.end(), b, b + 4);
}

// The code message, its length before it, appended to `out`.
bool put_tables(const CodeTables& tables, std::vector<uint8_t>& out) {
  uint8_t message[64 * 1024];
  const size_t bytes = write_code_tables(tables, message, sizeof message);
  if (bytes == 0) return false;
  put_u32(out, static_cast<uint32_t>(bytes));
  out.insert(out.end(), message, message + bytes);
  return true;
}

// One batch coded, its length before it, appended to `out`.
bool put_batch(const CodeTables& tables, const std::vector<CodedEntry>& batch, size_t record_bytes,
               std::vector<uint8_t>& out) {
  std::vector<uint8_t> coded(batch.size() * (record_bytes * 2 + 16) + 64);
  const size_t bytes = encode_coded_nodes(tables, batch.data(), static_cast<uint32_t>(batch.size()), coded.data(), coded.size());
  if (bytes == 0) return false;
  put_u32(out, static_cast<uint32_t>(bytes));
  out.insert(out.end(), coded.begin(), coded.begin() + static_cast<std::ptrdiff_t>(bytes));
  return true;
}

}  // namespace

bool write_coded_spg(const uint8_t* data, size_t size, std::vector<uint8_t>& out, CodedFileReport& report,
                     std::string& error, const std::function<void(double)>& progress) {
  SpgView view;
  if (const SpgResult r = spg_parse(data, size, &view); !r.ok())
    return error = std::string("version 3: the file to code is not a valid .spg (") + spg_error_text(r.error) + ")", false;
  const SpgHeader& h = view.header;
  if (h.version != kSpgVersion)
    return error = "version 3: codes version " + std::to_string(kSpgVersion) + " files (this is version " +
                   std::to_string(h.version) + ")",
           false;
  const uint32_t n = h.node_count;
  std::vector<uint8_t> points(n);
  spg_node_points(view, points.data(), 1);

  // The tables, from every unit as its batch will code it.
  const CodeTables tables = counted_tables(view, [&](auto&& f) { for_each_batch(view, points.data(), f); });

  // The file: version 2's sections before the records, then the coded ones.
  const size_t records_offset = static_cast<size_t>(view.records - data);
  out.assign(data, data + records_offset);
  store_u16le(out.data() + spg_offset::kVersion, kSpgCodedVersion);
  if (!put_tables(tables, out)) return error = "version 3: the code tables did not fit", false;
  const size_t tables_bytes = out.size() - records_offset - 4;
  const size_t count_at = out.size();
  put_u32(out, 0);
  std::vector<uint16_t> depth(n, 0);
  for (uint32_t id = 0, child = 1; id < n; ++id)
    for (uint32_t c = spg_child_count(view, id); c > 0; --c) depth[child++] = static_cast<uint16_t>(depth[id] + 1);
  std::vector<uint64_t> mean_q8(size_t{h.depth} + 1, 0);
  report.nodes_by_depth.assign(size_t{h.depth} + 1, 0);
  uint32_t batches = 0, done = 0;
  bool ok = true;
  for_each_batch(view, points.data(), [&](const std::vector<CodedEntry>& batch) {
    ok = ok && put_batch(tables, batch, view.record_bytes, out);
    for (size_t i = 0; i < batch.size();) {
      const uint32_t k = batch[i].kind == 1 ? 2 : 1;
      uint32_t cost[2];
      coded_mean_cost_q8(tables, &batch[i], cost);
      for (uint32_t j = 0; j < k; ++j) {
        mean_q8[depth[batch[i + j].id]] += cost[j];
        ++report.nodes_by_depth[depth[batch[i + j].id]];
      }
      i += k;
    }
    ++batches;
    done += static_cast<uint32_t>(batch.size());
    if (progress) progress(static_cast<double>(done) / n);
  });
  if (!ok) return error = "version 3: a batch could not be coded", false;
  store_u32le(out.data() + count_at, batches);
  put_u32(out, crc32(out.data(), out.size()));

  // Read back as every reader will: the very bytes it was given.
  SpgView coded_view;
  SpgCodedParts parts;
  if (const SpgResult r = spg_parse_coded(out.data(), out.size(), &coded_view, &parts); !r.ok())
    return error = std::string("version 3: wrote a file the reader refuses (") + spg_error_text(r.error) + ")", false;
  std::vector<uint8_t> image(spg_expanded_bytes(coded_view, parts)), scratch(n);
  if (const SpgResult r = spg_expand(out.data(), coded_view, parts, image.data(), scratch.data()); !r.ok())
    return error = std::string("version 3: wrote records that do not decode (") + spg_error_text(r.error) + ")", false;
  if (image.size() != size || !std::equal(image.begin(), image.end(), data))
    return error = "version 3: the coded file does not expand to the file it was made from", false;
  report.mean_bits_by_depth.assign(mean_q8.size(), 0.0);
  for (size_t d = 0; d < mean_q8.size(); ++d)
    if (report.nodes_by_depth[d] > 0) report.mean_bits_by_depth[d] = static_cast<double>(mean_q8[d]) / 256.0 / report.nodes_by_depth[d];
  report.records_bytes = size_t{n} * view.record_bytes;
  report.tables_bytes = tables_bytes;
  report.coded_bytes = out.size() - 4 - records_offset;
  report.file_bytes = out.size();
  report.batches = batches;
  return true;
}

size_t coded_cut_bytes(const SpgView& view, const std::vector<uint32_t>& cut) {
  std::vector<uint8_t> points(view.header.node_count);
  spg_node_points(view, points.data(), 1);
  const auto fields = [&](uint32_t id) { return unpack_record(view.header.layout, view.records + size_t{id} * view.record_bytes); };
  // Each node against the one before it in the cut, in batches as a file's.
  std::vector<std::vector<CodedEntry>> batches;
  for (size_t i = 0; i < cut.size(); ++i) {
    if (i % kSpgCodedBatchNodes == 0) batches.emplace_back();
    CodedEntry e;
    e.id = cut[i];
    e.points = points[cut[i]];
    e.fields = fields(cut[i]);
    if (i > 0) {
      e.reference_id = cut[i - 1];
      e.reference = fields(cut[i - 1]);
    }
    batches.back().push_back(e);
  }
  const CodeTables tables = counted_tables(view, [&](auto&& f) {
    for (const std::vector<CodedEntry>& b : batches) f(b);
  });
  std::vector<uint8_t> out;
  bool ok = put_tables(tables, out);
  put_u32(out, static_cast<uint32_t>(batches.size()));
  for (const std::vector<CodedEntry>& b : batches) ok = ok && put_batch(tables, b, view.record_bytes, out);
  return ok ? out.size() : 0;
}

}  // namespace stipple
