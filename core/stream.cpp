// stipple core — the two ends of a node stream. See stream.h and docs/protocol.md.
#include "core/stream.h"

#include <algorithm>
#include <new>

#include "core/arena.h"

#include "core/spg_writer.h"

namespace stipple {
namespace {

bool is_normal_field(int f) { return f >= static_cast<int>(Field::kFnTheta) && f <= static_cast<int>(Field::kSigmaN); }
bool is_color_field(int f) { return f >= static_cast<int>(Field::kColorR); }

// Class `index` of `table` as the client with `reduced` reads it (.spg §2
// values): sigma_n's magnitudes where the model is signed and the client
// did not ask for the sign.
void copy_class_values(const SpgView& view, const SpgHeader& reduced, int table, uint32_t index, uint8_t* out) {
  const uint8_t* tables[3] = {view.sigma_p, view.sigma_n, view.sigma_c};
  const size_t per = spg_class_values(table) * spg_class_value_bytes(view.header.version);
  const uint8_t* in = tables[table] + per * index;
  for (size_t b = 0; b < per; ++b) out[b] = in[b];
  if (table == 1 && spg_sigma_n_unsigned_for(view.header, reduced))
    for (size_t b = 0; b < per; b += 2) store_u16le(out + b, spg_sigma_n_magnitude(load_u16le(out + b), true));
}

}  // namespace

SpgHeader reduced_header(const SpgHeader& full, uint8_t attributes) {
  SpgHeader h = full;
  const bool normals = full.has_normals() && (attributes & kWantNormals);
  const bool color = full.has_color() && (attributes & kWantColor);
  const bool sign = normals && full.has_curvature_sign() && (attributes & kWantCurvatureSign);
  h.flags = static_cast<uint16_t>((normals ? kAttrNormals : 0) | (color ? kAttrColor : 0) | (sign ? kAttrCurvatureSign : 0));
  for (int f = 0; f < kFieldCount; ++f)
    if ((!normals && is_normal_field(f)) || (!color && is_color_field(f))) h.layout.bits[f] = 0;
  if (!normals) h.class_count[1] = 0;
  if (!color) h.class_count[2] = 0;
  return h;
}

void transcode_record(const RecordLayout& from, const RecordLayout& to, const uint8_t* in, uint8_t* out) {
  NodeFields f = unpack_record(from, in);
  for (int k = 0; k < kFieldCount; ++k)
    if (to.bits[k] == 0) f.v[k] = 0;
  pack_record(to, f, out);
}

namespace {

constexpr Field kClassField[3] = {Field::kSigmaP, Field::kSigmaN, Field::kSigmaC};
constexpr uint32_t kNoGroup = 0xFFFFFFFFu;

// The first index of ascending ids[0 .. n) at or above `id` (n: none).
uint32_t first_at_or_above(const uint32_t* ids, uint32_t n, uint32_t id) {
  return static_cast<uint32_t>(std::lower_bound(ids, ids + n, id) - ids);
}
uint32_t first_at_or_above(const NodeId* ids, uint32_t n, uint32_t id) {
  return static_cast<uint32_t>(std::lower_bound(ids, ids + n, id, [](NodeId a, uint32_t b) { return index_of(a) < b; }) - ids);
}

}  // namespace

size_t write_reduced_startup(const SpgView& view, uint8_t attributes, uint8_t* out, size_t capacity) {
  const SpgHeader h = reduced_header(view.header, attributes);
  size_t written = 0;
  if (spg_write_startup_le(h, view.sigma_p, h.class_count[1] ? view.sigma_n : nullptr,
                           h.class_count[2] ? view.sigma_c : nullptr, out, capacity, &written) != SpgWriteStatus::kOk)
    return 0;
  if (h.class_count[1] > 0 && spg_sigma_n_unsigned_for(view.header, h)) {
    // A client without the sign: the sigma_n classes' magnitudes.
    uint8_t* sigma_n = out + spg_fixed_header_bytes(h.version) + 6 * size_t{h.class_count[0]};
    for (uint32_t c = 0; c < h.class_count[1]; ++c) copy_class_values(view, h, 1, c, sigma_n + 4 * size_t{c});
  }
  return written;
}

size_t SenderScratch::bytes(uint32_t cut_capacity) {
  return align8(kMaxPayload) + align8(kMaxFrameBytes) + align8(sizeof(CodeTableCache)) + 25 * (size_t{cut_capacity} + 8) +
         CutScratch::bytes(cut_capacity + 8);
}

void SenderScratch::init(void* storage, size_t size) {
  uint8_t* base = static_cast<uint8_t*>(storage);
  const size_t fixed = align8(kMaxPayload) + align8(kMaxFrameBytes) + align8(sizeof(CodeTableCache));
  payload = size < fixed ? nullptr : base;
  frame = size < fixed ? nullptr : base + align8(kMaxPayload);
  codes = size < fixed ? nullptr : new (base + align8(kMaxPayload) + align8(kMaxFrameBytes)) CodeTableCache;
  // The rest: 25 bytes a node for the order, 32 for the cut's scratch.
  const size_t per_node = 25 + CutScratch::bytes(1);
  const size_t fit = size < fixed ? 0 : (size - fixed) / per_node;
  const uint32_t n = static_cast<uint32_t>(fit < 0x7FFFFFF0u ? fit : 0x7FFFFFF0u) & ~7u;  // the cut's part stays 8-aligned
  order_capacity = n;
  order = reinterpret_cast<uint64_t*>(base + fixed);
  left = reinterpret_cast<uint32_t*>(order + n);
  waiting = left + n;
  ready = waiting + n;
  sent = reinterpret_cast<uint8_t*>(ready + n);
  cut.init(sent + n, size < fixed ? 0 : size - fixed - 25 * size_t{n});
}

size_t StreamSender::storage_bytes(const SpgHeader& header) {
  return view_cut_state_bytes(header.node_count) + align8(class_bits_bytes(header)) + SenderScratch::bytes(header.node_count);
}

bool StreamSender::init(const SpgView& view, const CutBounds& bounds, void* storage, size_t bytes) {
  if (bytes < storage_bytes(view.header)) return false;
  const size_t state_bytes = view_cut_state_bytes(view.header.node_count);
  const size_t bits = align8(class_bits_bytes(view.header));
  own_scratch_.init(static_cast<uint8_t*>(storage) + state_bytes + bits, bytes - state_bytes - bits);
  if (!init(view, bounds, storage, state_bytes, &own_scratch_)) return false;
  use_class_bits(static_cast<uint8_t*>(storage) + state_bytes, bits);
  return true;
}

bool StreamSender::init(const SpgView& view, const CutBounds& bounds, void* state, size_t state_bytes,
                        const SenderScratch* scratch) {
  if (scratch == nullptr || scratch->payload == nullptr) return false;
  if (cut_.init(bounds, state, state_bytes, &scratch->cut) != CutStatus::kOk) return false;
  scratch_ = scratch;
  view_ = &view;
  started_ = false;
  sequence_ = 0;
  bytes_sent_ = 0;
  cut_status_ = CutStatus::kOk;
  return true;
}

void StreamSender::use_scratch(const SenderScratch* scratch) {
  scratch_ = scratch;
  cut_.use_scratch(&scratch->cut);
}

bool StreamSender::send(MessageType type, const uint8_t* payload, size_t size, FrameSink sink, void* context) {
  if (scratch_ == nullptr) return false;
  const size_t n = write_frame(type, sequence_, payload, size, scratch_->frame, kMaxFrameBytes);
  if (n == 0 || !sink(context, scratch_->frame, n)) return false;
  ++sequence_;
  bytes_sent_ += n;
  return true;
}

uint8_t StreamSender::adopt_hello(const Hello& hello) {
  const uint8_t attributes = static_cast<uint8_t>(hello.attributes & ~kResuming);
  reduced_ = reduced_header(view_->header, attributes);
  reduced_record_bytes_ = static_cast<size_t>(reduced_.layout.record_bytes());
  same_layout_ = true;
  for (int f = 0; f < kFieldCount; ++f) same_layout_ = same_layout_ && reduced_.layout.bits[f] == view_->header.layout.bits[f];
  capacity_ = hello.cache_capacity;
  pieces_ = hello.version >= 4 && class_bits_ != nullptr && class_bits_bytes_ >= class_bits_bytes(reduced_);
  for (size_t i = 0; pieces_ && i < class_bits_bytes(reduced_); ++i) class_bits_[i] = 0;
  coded_ = pieces_ && hello.version >= 5 && (hello.attributes & kWantCoded) && scratch_->codes != nullptr;
  protocol_ = hello.version;
  tables_sent_ = false;
  return static_cast<uint8_t>(attributes & ~kWantCoded);
}

bool StreamSender::start(const Hello& hello, FrameSink sink, void* context) {
  if (view_ == nullptr || hello.version < kOldestProtocolVersion || hello.version > kProtocolVersion) return false;
  const uint8_t attributes = adopt_hello(hello);
  cut_.reset();  // a fresh client: its cut starts empty, so the first update sends it all
  uint8_t* payload = scratch_->payload;
  started_ = true;
  sequence_ = 0;  // a new stream (a serial client says hello again to resynchronise)
  if (pieces_) {
    // The model: its tag and header; each class comes before its first node.
    const size_t n = write_reduced_startup(*view_, attributes, payload + kModelTagBytes, kMaxPayload - kModelTagBytes);
    if (n == 0) return started_ = false;
    store_u32le(payload, crc32(payload + kModelTagBytes, n));
    return send(MessageType::kModel, payload, kModelTagBytes + spg_fixed_header_bytes(reduced_.version), sink, context);
  }
  const size_t n = write_reduced_startup(*view_, attributes, payload, kMaxPayload);
  if (n == 0) return started_ = false;
  return send(MessageType::kStartup, payload, n, sink, context);
}

uint32_t StreamSender::model_tag(uint8_t attributes) const {
  if (view_ == nullptr || scratch_ == nullptr) return 0;
  const size_t n = write_reduced_startup(*view_, static_cast<uint8_t>(attributes & ~kResuming), scratch_->payload, kMaxPayload);
  return n == 0 ? 0 : crc32(scratch_->payload, n);
}

bool StreamSender::take_class(int table, uint32_t index) {
  const size_t bit = spg_class_bit(reduced_, table, index);
  const uint8_t mask = static_cast<uint8_t>(1u << (bit % 8));
  if (class_bits_[bit / 8] & mask) return false;
  class_bits_[bit / 8] = static_cast<uint8_t>(class_bits_[bit / 8] | mask);
  return true;
}

bool StreamSender::resume(const Hello& hello, const NodeId* held, uint32_t count, FrameSink sink, void* context) {
  if (view_ == nullptr || scratch_ == nullptr || hello.version < 3) return false;
  (void)adopt_hello(hello);
  if (!cut_.adopt_sent(held, count)) return false;
  if (pieces_) {
    // The client holds at least the classes its nodes use.
    for (uint32_t i = 0; i < count; ++i) {
      const NodeFields f = unpack_record(view_->header.layout, view_->records + size_t{index_of(held[i])} * view_->record_bytes);
      for (int t = 0; t < 3; ++t)
        if (reduced_.class_count[t] > 0) (void)take_class(t, f[kClassField[t]]);
    }
  }
  started_ = true;
  sequence_ = 0;
  uint8_t payload[4];
  store_u32le(payload, count);
  return send(MessageType::kResumed, payload, 4, sink, context);
}

const CodeTables& StreamSender::code_tables() {
  // Counted from a sample of the model's records, once per worker and
  // attribute set: deterministic, so every worker counts the same tables.
  constexpr uint32_t kSample = 32768;
  CodeTableCache& c = *scratch_->codes;
  if (c.view != view_) {
    c.view = view_;
    c.built = 0;
  }
  // A version 5 client reads tables without the frame fields and without
  // a class piece's first values as differences: built apart.
  const int k = (reduced_.flags & (kAttrNormals | kAttrColor | kAttrCurvatureSign)) | (protocol_ < kFrameFieldsProtocol ? 8 : 0);
  if (!(c.built & (1u << k))) {
    build_code_tables(*view_, cut_, reduced_, kSample, &c.tables[k], protocol_);
    c.built = static_cast<uint16_t>(c.built | (1u << k));
  }
  return c.tables[k];
}

bool StreamSender::send_code_tables(FrameSink sink, void* context) {
  const size_t n = write_code_tables(code_tables(), scratch_->payload, kMaxPayload);
  if (n == 0 || !send(MessageType::kCode, scratch_->payload, n, sink, context)) return false;
  tables_sent_ = true;
  return true;
}

bool StreamSender::send_coded(const uint64_t* keyed, uint32_t count, FrameSink sink, void* context) {
  // keyed[i]: an entering node's id (high word, ascending) and the node that
  // left which it refines (low word: its index in scratch_->left, or
  // kNoGroup). Two that are the only children of the node they refine go
  // as a split against it: the client holds it until they have come. Any
  // other entry's reference is the entering node nearest to it among those
  // this part has sent (scratch_->sent, by the entering nodes' ascending
  // ids), earlier entries of this batch included. The entries are laid
  // out in the frame buffer, which send() fills only once a batch is coded
  // into the payload.
  constexpr uint32_t kMost = 1024;
  static_assert(kMost * sizeof(CodedEntry) <= kMaxFrameBytes);
  CodedEntry* entries = reinterpret_cast<CodedEntry*>(scratch_->frame);
  const NodeId* entered = cut_.entered();
  const uint32_t entering = cut_.entered_count();
  uint8_t* sent = scratch_->sent;
  const auto fields_of = [&](uint32_t id) {
    return unpack_record(view_->header.layout, view_->records + size_t{id} * view_->record_bytes);
  };
  const auto parent_of_split = [&](uint32_t i) {  // the parent when keyed[i], keyed[i + 1] are a split
    if (!splits_ || i + 1 >= count) return kNoGroup;
    const uint32_t id = static_cast<uint32_t>(keyed[i] >> 32), group = static_cast<uint32_t>(keyed[i]);
    if (group == kNoGroup || keyed[i + 1] != ((uint64_t{id + 1} << 32) | group)) return kNoGroup;
    const uint32_t parent = scratch_->left[group];
    return cut_.first_child(parent) == id && cut_.first_child(parent + 1) == id + 2 ? parent : kNoGroup;
  };
  for (uint32_t done = 0; done < count;) {
    uint32_t n = 0;
    while (done + n < count && n < kMost) {
      const uint32_t id = static_cast<uint32_t>(keyed[done + n] >> 32);
      uint32_t at = first_at_or_above(entered, entering, id);
      if (at == entering || index_of(entered[at]) != id) return false;  // not an entering node
      CodedEntry& e = entries[n];
      e.id = id;
      e.points = cut_.points(NodeId{id});
      e.fields = fields_of(id);
      const uint32_t parent = n + 2 <= kMost ? parent_of_split(done + n) : kNoGroup;
      if (parent != kNoGroup) {
        e.kind = 1;
        e.reference_id = parent;
        e.reference = fields_of(parent);
        e.reference_points = cut_.points(NodeId{parent});
        CodedEntry& second = entries[n + 1];
        second.kind = 2;
        second.id = id + 1;
        second.points = cut_.points(NodeId{id + 1});
        second.fields = fields_of(id + 1);
        sent[at] = sent[at + 1] = 1;  // entered[at + 1] is id + 1: both enter
        ++splits_sent_;
        n += 2;
        continue;
      }
      sent[at] = 1;
      uint32_t below = at, above = at + 1;
      while (below > 0 && !sent[below - 1]) --below;
      while (above < entering && !sent[above]) ++above;
      e.kind = 0;
      e.reference_id = coded_reference(id, below > 0 ? index_of(entered[below - 1]) : 0xFFFFFFFFu,
                                       above < entering ? index_of(entered[above]) : 0xFFFFFFFFu);
      e.reference = e.reference_id != 0xFFFFFFFFu ? fields_of(e.reference_id) : NodeFields{};
      ++n;
    }
    const size_t bytes = encode_coded_nodes(code_tables(), entries, n, scratch_->payload, kMaxPayload);
    if (bytes == 0 || !send(MessageType::kCodedNodes, scratch_->payload, bytes, sink, context)) return false;
    done += n;
  }
  return true;
}

bool StreamSender::update(const CameraUpdate& camera, bool cull, FrameSink sink, void* context) {
  if (!started_) return false;
  CutParams p;
  p.max_size_q4 = camera.max_size_q4;
  p.max_nodes = capacity_;
  p.cull_frustum = p.cull_backfaces = cull;
  for (int k = 0; k < 4; ++k) p.window[k] = camera.window[k];
  p.accumulate = camera.accumulate;
  const bool cold = cut_.sent_count() == 0;
  if (cold && capacity_ > kCoarseNodes) {
    // A cold start: a whole coarse picture first, then its refinement.
    CutParams coarse = p;
    coarse.max_nodes = kCoarseNodes;
    cut_status_ = cut_.update(camera.camera, coarse);
    // Its few batches go compact: the code tables wait for the refinement.
    coarse_ = true;
    const bool sent = cut_status_ == CutStatus::kOk && send_change(camera.sequence, 1, true, sink, context);
    coarse_ = false;
    if (!sent) return false;
  }
  cut_status_ = cut_.update(camera.camera, p);
  if (cut_status_ != CutStatus::kOk || !send_change(camera.sequence, 0, cold, sink, context)) return false;
  const UpdateEnd end{camera.sequence, cut_.sent_count()};
  uint8_t buf[kUpdateEndBytes];
  write_update_end(end, buf);
  return send(MessageType::kUpdateEnd, buf, kUpdateEndBytes, sink, context);
}

bool StreamSender::send_classes(const uint64_t* order, uint32_t count, FrameSink sink, void* context) {
  // The classes these nodes use that have not been sent, by table.
  constexpr uint32_t kMost = 2048;  // a batch's nodes at most (count <= per_frame)
  uint16_t fresh[3][kMost];
  uint32_t n[3] = {};
  for (uint32_t i = 0; i < count && i < kMost; ++i) {
    const uint32_t id = ~static_cast<uint32_t>(order[i]);
    const NodeFields f = unpack_record(view_->header.layout, view_->records + size_t{id} * view_->record_bytes);
    for (int t = 0; t < 3; ++t)
      if (reduced_.class_count[t] > 0 && take_class(t, f[kClassField[t]])) fresh[t][n[t]++] = static_cast<uint16_t>(f[kClassField[t]]);
  }
  uint8_t* payload = scratch_->payload;
  // Once the code tables went (protocol 5, format version 2 on), classes go coded.
  const CodeTables* code = tables_sent_ && reduced_.version >= 2 ? &code_tables() : nullptr;
  for (int t = 0; t < 3; ++t) {
    if (n[t] == 0) continue;
    std::sort(fresh[t], fresh[t] + n[t]);
    if (code != nullptr) {
      // The values in index order, laid out in the frame buffer until send() fills it.
      const size_t per = 2 * spg_class_values(t);
      uint8_t* values = scratch_->frame;
      for (uint32_t k = 0; k < n[t]; ++k)
        copy_class_values(*view_, reduced_, t, fresh[t][k], values + per * k);
      const size_t bytes = encode_coded_classes(*code, t, fresh[t], values, n[t], payload, kMaxPayload);
      if (bytes == 0 || !send(MessageType::kCodedClasses, payload, bytes, sink, context)) return false;
      continue;
    }
    const size_t per = spg_class_values(t) * spg_class_value_bytes(view_->header.version);
    size_t at = kClassesHeaderBytes;
    uint32_t previous = 0xFFFFFFFFu;
    for (uint32_t k = 0; k < n[t]; ++k) {
      at += store_leb128(payload + at, fresh[t][k] - previous);  // the first from -1
      previous = fresh[t][k];
      copy_class_values(*view_, reduced_, t, fresh[t][k], payload + at);
      at += per;
    }
    write_classes_header(static_cast<uint8_t>(t), static_cast<uint16_t>(n[t]), payload);
    if (!send(MessageType::kClasses, payload, at, sink, context)) return false;
  }
  return true;
}

size_t StreamSender::put_id(uint8_t* out, uint32_t id, uint32_t previous) const {
  if (pieces_) return store_leb128(out, id - previous);  // from -1 for the first: id + 1
  store_u32le(out, id);
  return 4;
}

bool StreamSender::send_drops(uint32_t* ids, uint32_t count, FrameSink sink, void* context) {
  uint8_t* payload = scratch_->payload;
  if (pieces_) std::sort(ids, ids + count);  // compact: ascending differences
  for (uint32_t done = 0; done < count;) {
    const uint32_t n = count - done < kDropsPerFrame ? count - done : kDropsPerFrame;
    store_u32le(payload, n);
    size_t at = 4;
    uint32_t previous = 0xFFFFFFFFu;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t id = ids[done + i];
      at += put_id(payload + at, id, previous);
      previous = id;
    }
    if (!send(MessageType::kDrop, payload, at, sink, context)) return false;
    done += n;
  }
  return true;
}

bool StreamSender::send_nodes(const uint64_t* order, uint32_t count, FrameSink sink, void* context) {
  // The code tables just before the first coded batch and its classes.
  if (coded_ && part_sent_ && !tables_sent_ && !send_code_tables(sink, context)) return false;
  if (pieces_ && !send_classes(order, count, sink, context)) return false;
  uint8_t* payload = scratch_->payload;
  // Compact batches go in id order (the order within a batch draws nothing
  // different: a batch is applied whole).
  uint32_t ids[2048];
  if (count > 2048) return false;  // batches hold at most kNodeBatchBytes
  if (coded_ && part_sent_) {
    // Each id with the node that left which it refines (the order's high word).
    uint64_t keyed[2048];
    for (uint32_t i = 0; i < count; ++i) keyed[i] = (uint64_t{~static_cast<uint32_t>(order[i])} << 32) | (order[i] >> 32);
    std::sort(keyed, keyed + count);
    return send_coded(keyed, count, sink, context);
  }
  for (uint32_t i = 0; i < count; ++i) ids[i] = ~static_cast<uint32_t>(order[i]);
  if (pieces_) std::sort(ids, ids + count);
  store_u32le(payload, count);
  size_t at = 4;
  uint32_t previous = 0xFFFFFFFFu;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t id = ids[i];
    at += put_id(payload + at, id, previous);
    previous = id;
    payload[at++] = cut_.points(NodeId{id});
    const uint8_t* record = view_->records + size_t{id} * view_->record_bytes;
    if (same_layout_)
      for (size_t b = 0; b < reduced_record_bytes_; ++b) payload[at + b] = record[b];
    else
      transcode_record(view_->header.layout, reduced_.layout, record, payload + at);
    at += reduced_record_bytes_;
  }
  return send(MessageType::kNodes, payload, at, sink, context);
}

bool StreamSender::send_change(uint32_t sequence, uint8_t parts_after, bool ramp, FrameSink sink, void* context) {
  const SenderScratch& s = *scratch_;
  const uint32_t entering = cut_.entered_count(), leaving = cut_.left_count();
  if (pieces_) {
    uint8_t begin[kUpdateBeginBytes];
    write_update_begin(UpdateBegin{sequence, entering, leaving, parts_after}, begin);
    if (!send(MessageType::kUpdateBegin, begin, kUpdateBeginBytes, sink, context)) return false;
  }
  const size_t stride = node_entry_bytes(reduced_record_bytes_);
  const uint32_t per_frame = static_cast<uint32_t>((kNodeBatchBytes - 4) / stride);
  uint64_t* order = s.order;
  uint32_t* left = s.left;
  uint32_t* waiting = s.waiting;
  const uint32_t held_before = cut_.sent_count() - entering + leaving;
  // Entering nodes by projected size, largest first (ties: smaller id).
  // Without sizes (an incremental cut) or room, they keep the id order.
  const bool sized = cut_.sent_size_q4() != nullptr && entering <= s.order_capacity && leaving <= s.order_capacity;
  // Coded batches refer to what this part sent before them: kept by the
  // entering nodes' positions. Without room, the part's batches go compact.
  part_sent_ = sized && !coarse_;
  for (uint32_t i = 0; part_sent_ && i < entering; ++i) s.sent[i] = 0;
  if (!sized) {
    // The plain order: every drop, then the nodes in id order.
    uint32_t ids[1024];
    for (uint32_t done = 0; done < leaving;) {
      const uint32_t n = leaving - done < 1024 ? leaving - done : 1024;
      for (uint32_t i = 0; i < n; ++i) ids[i] = index_of(cut_.left()[done + i]);
      if (!send_drops(ids, n, sink, context)) return false;
      done += n;
    }
    uint64_t batch[1024];
    const uint32_t most = per_frame < 1024 ? per_frame : 1024;
    for (uint32_t done = 0; done < entering;) {
      const uint32_t n = entering - done < most ? entering - done : most;
      for (uint32_t i = 0; i < n; ++i) batch[i] = ~index_of(cut_.entered()[done + i]);
      if (!send_nodes(batch, n, sink, context)) return false;
      done += n;
    }
    return true;
  }
  // A cut with sizes came from the root: its change is in id order. The
  // key's low word is the entering node's index, inverted (ties: the
  // smaller id first, as the ids ascend with the index).
  const NodeId* entered = cut_.entered();
  {
    const NodeId* sent = cut_.sent();
    const uint32_t* size = cut_.sent_size_q4();
    for (uint32_t i = 0, k = 0; i < entering; ++i) {
      while (sent[k] != entered[i]) ++k;  // entered is a subset of sent, both ascending
      order[i] = (uint64_t{size[k]} << 32) | (~i & 0xFFFFFFFFu);
    }
  }
  for (uint32_t i = 0; i < leaving; ++i) {
    left[i] = index_of(cut_.left()[i]);
    waiting[i] = 0;
  }
  // Which node that left each entering node refines: the old cut and the
  // new are antichains, so an entering node lies below at most one node that
  // left, and a node's descendants are one id range a level — two binary
  // searches of the (ascending) entering ids a level below each node that
  // left. `ready` holds each entering node's group until the order is made.
  uint32_t* group_of = s.ready;
  for (uint32_t i = 0; i < entering; ++i) group_of[i] = kNoGroup;
  uint32_t unrefined = 0;
  for (uint32_t j = 0; j < leaving; ++j) {
    for (uint32_t lo = cut_.first_child(left[j]), hi = cut_.first_child(left[j] + 1); lo < hi;
         lo = cut_.first_child(lo), hi = cut_.first_child(hi)) {
      const uint32_t from = first_at_or_above(entered, entering, lo), to = first_at_or_above(entered, entering, hi);
      for (uint32_t i = from; i < to; ++i) group_of[i] = j;
      waiting[j] += to - from;
    }
    unrefined += waiting[j] == 0;
  }
  // Nodes that left with nothing below them entering: merged into an
  // entering ancestor (dropped after the nodes: kNoGroup), or gone from view.
  for (uint32_t i = 0; i < entering && unrefined > 0; ++i) {
    const uint32_t e = index_of(entered[i]);
    for (uint32_t lo = cut_.first_child(e), hi = cut_.first_child(e + 1); lo < hi;
         lo = cut_.first_child(lo), hi = cut_.first_child(hi))
      for (uint32_t j = first_at_or_above(left, leaving, lo); j < leaving && left[j] < hi; ++j)
        if (waiting[j] == 0) {
          waiting[j] = kNoGroup;
          --unrefined;
        }
  }
  std::sort(order, order + entering, [](uint64_t a, uint64_t b) { return a > b; });
  // Then the order holds each node's group and id (inverted, as send_nodes
  // takes them) in place of its size and index.
  for (uint32_t k = 0; k < entering; ++k) {
    const uint32_t i = ~static_cast<uint32_t>(order[k]);
    order[k] = (uint64_t{group_of[i]} << 32) | (~index_of(entered[i]) & 0xFFFFFFFFu);
  }
  // A cache that cannot hold both what it has and what comes: drops first.
  const bool room = uint64_t{held_before} + entering <= capacity_;
  // Splits (coded batches) refer to their parent: only while it is held.
  splits_ = room && split_deltas_;
  uint32_t* ready = s.ready;
  uint32_t ready_count = 0;
  if (!room) {
    if (!send_drops(left, leaving, sink, context)) return false;
  } else {
    // Nodes that left gone from view go now; merged ones at the end.
    for (uint32_t j = 0; j < leaving; ++j)
      if (waiting[j] == 0) ready[ready_count++] = left[j];
    if (!send_drops(ready, ready_count, sink, context)) return false;
    ready_count = 0;
  }
  // A client that holds nothing gets its first nodes in small batches, so
  // the first of them (and the classes they use) arrive soonest.
  for (uint32_t done = 0, batch = 0; done < entering; ++batch) {
    const uint32_t most = ramp && batch < 3 && (16u << (2 * batch)) < per_frame ? 16u << (2 * batch) : per_frame;
    const uint32_t n = entering - done < most ? entering - done : most;
    if (!send_nodes(order + done, n, sink, context)) return false;
    if (room) {
      for (uint32_t i = done; i < done + n; ++i) {
        const uint32_t g = static_cast<uint32_t>(order[i] >> 32);
        if (g != kNoGroup && --waiting[g] == 0) ready[ready_count++] = left[g];
      }
      if (!send_drops(ready, ready_count, sink, context)) return false;
      ready_count = 0;
    }
    done += n;
  }
  if (room) {
    for (uint32_t j = 0; j < leaving; ++j)
      if (waiting[j] == kNoGroup) ready[ready_count++] = left[j];
    if (!send_drops(ready, ready_count, sink, context)) return false;
  }
  return true;
}

const char* receive_status_text(ReceiveStatus s) {
  switch (s) {
    case ReceiveStatus::kOk: return "ok";
    case ReceiveStatus::kBadFrame: return "a frame was refused";
    case ReceiveStatus::kBadMessage: return "a message was malformed or out of order";
    case ReceiveStatus::kCacheRefused: return "the node cache refused the startup or a node";
    case ReceiveStatus::kClosed: return "the server closed the stream";
  }
  return "unknown status";
}

void StreamReceiver::init(NodeCache* cache, uint8_t* reader_storage, size_t bytes) {
  cache_ = cache;
  reader_.init(reader_storage, bytes);
  status_ = ReceiveStatus::kOk;
  frame_status_ = FrameStatus::kOk;
  cache_status_ = CacheStatus::kOk;
  fault_ = Fault{};
  has_update_end_ = false;
  part_ = UpdateBegin{};
  part_nodes_ = 0;
  bytes_ = nodes_ = 0;  // startup_crc_ stays: it is the cache's, which init keeps
  frames_ = 0;
}

ReceiveStatus StreamReceiver::apply(const Frame& f) {
  ++frames_;
  const auto refused = [&](CacheStatus s) {
    cache_status_ = s;
    return ReceiveStatus::kCacheRefused;
  };
  switch (f.type) {
    case MessageType::kStartup: {
      const CacheStatus s = cache_->load_startup(f.payload, f.payload_bytes);
      if (s != CacheStatus::kOk) return refused(s);
      startup_crc_ = crc32(f.payload, f.payload_bytes);
      compact_ = coded_ = false;
      has_update_end_ = false;
      return ReceiveStatus::kOk;
    }
    case MessageType::kModel: {
      if (f.payload_bytes < kModelTagBytes) return ReceiveStatus::kBadMessage;
      const CacheStatus s = cache_->load_model(f.payload + kModelTagBytes, f.payload_bytes - kModelTagBytes);
      if (s != CacheStatus::kOk) return refused(s);
      startup_crc_ = load_u32le(f.payload);
      compact_ = true;
      coded_ = false;
      part_count_ = 0;
      has_update_end_ = false;
      part_ = UpdateBegin{};
      return ReceiveStatus::kOk;
    }
    case MessageType::kClasses: {
      ClassesPiece c;
      if (!cache_->ready() || !parse_classes(f.payload, f.payload_bytes, &c) || cache_->header().class_count[c.table] == 0)
        return ReceiveStatus::kBadMessage;
      const uint8_t* at = c.entries;
      const uint8_t* end = c.entries + c.entries_bytes;
      const size_t value_bytes = cache_->class_value_bytes(c.table);
      uint32_t previous = 0xFFFFFFFFu;
      for (uint32_t i = 0; i < c.count; ++i) {
        uint32_t index = 0;
        const uint8_t* values = nullptr;
        if (!next_class_entry(&at, end, value_bytes, &previous, &index, &values)) return ReceiveStatus::kBadMessage;
        const CacheStatus s = cache_->add_class(c.table, index, values, value_bytes);
        if (s != CacheStatus::kOk) return refused(s);
      }
      return at == end ? ReceiveStatus::kOk : ReceiveStatus::kBadMessage;
    }
    case MessageType::kCode: {
      if (!cache_->ready() || !compact_ || part_ids_ == nullptr ||
          !parse_code_tables(f.payload, f.payload_bytes, cache_->header(), &code_))
        return ReceiveStatus::kBadMessage;
      coded_ = true;
      return ReceiveStatus::kOk;
    }
    case MessageType::kCodedNodes: return apply_coded(f);
    case MessageType::kCodedClasses: {
      CodedClassesReader c;
      if (!coded_ || !c.init(code_, f.payload, f.payload_bytes)) return ReceiveStatus::kBadMessage;
      for (uint32_t i = 0; i < c.count(); ++i) {
        uint32_t index = 0;
        uint8_t values[6];
        if (!c.next(&index, values)) return ReceiveStatus::kBadMessage;
        const CacheStatus s = cache_->add_class(c.table(), index, values, cache_->class_value_bytes(c.table()));
        if (s != CacheStatus::kOk) return refused(s);
      }
      return c.finish() ? ReceiveStatus::kOk : ReceiveStatus::kBadMessage;
    }
    case MessageType::kUpdateBegin: {
      UpdateBegin u;
      if (!cache_->ready() || !parse_update_begin(f.payload, f.payload_bytes, &u)) return ReceiveStatus::kBadMessage;
      part_ = u;
      part_nodes_ = 0;
      part_count_ = 0;
      return ReceiveStatus::kOk;
    }
    case MessageType::kNodes: {
      if (compact_) {
        CompactBatch b;
        if (!cache_->ready() ||
            !parse_compact_nodes(f.payload, f.payload_bytes, cache_->record_bytes(), cache_->header().node_count, &b))
          return ReceiveStatus::kBadMessage;
        for (uint32_t i = 0; i < b.count; ++i) {
          uint32_t id = 0;
          uint8_t points = 0;
          const uint8_t* record = nullptr;
          next_compact(&b, &id, &points, &record);
          const CacheStatus s = cache_->put(NodeId{id}, record, b.record_bytes, points);
          if (s != CacheStatus::kOk) return refused(s);
        }
        nodes_ += b.count;
        part_nodes_ += b.count;
        return ReceiveStatus::kOk;
      }
      NodeBatch b;
      if (!cache_->ready() ||
          !parse_nodes(f.payload, f.payload_bytes, cache_->record_bytes(), cache_->header().node_count, &b))
        return ReceiveStatus::kBadMessage;
      for (uint32_t i = 0; i < b.count; ++i) {
        const CacheStatus s = cache_->put(b.id(i), b.record(i), b.record_bytes, b.points(i));
        if (s != CacheStatus::kOk) return refused(s);
      }
      nodes_ += b.count;
      part_nodes_ += b.count;
      return ReceiveStatus::kOk;
    }
    case MessageType::kDrop: {
      if (compact_) {
        CompactBatch b;
        if (!cache_->ready() || !parse_compact_drop(f.payload, f.payload_bytes, cache_->header().node_count, &b))
          return ReceiveStatus::kBadMessage;
        for (uint32_t i = 0; i < b.count; ++i) {
          uint32_t id = 0;
          next_compact(&b, &id, nullptr, nullptr);
          const CacheStatus s = cache_->drop(NodeId{id});
          if (s != CacheStatus::kOk) return refused(s);
        }
        return ReceiveStatus::kOk;
      }
      DropBatch b;
      if (!cache_->ready() || !parse_drop(f.payload, f.payload_bytes, cache_->header().node_count, &b))
        return ReceiveStatus::kBadMessage;
      for (uint32_t i = 0; i < b.count; ++i) {
        const CacheStatus s = cache_->drop(b.id(i));
        if (s != CacheStatus::kOk) return refused(s);
      }
      return ReceiveStatus::kOk;
    }
    case MessageType::kUpdateEnd: {
      UpdateEnd u;
      if (!parse_update_end(f.payload, f.payload_bytes, &u)) return ReceiveStatus::kBadMessage;
      last_update_ = u;
      has_update_end_ = true;
      return ReceiveStatus::kOk;
    }
    case MessageType::kKeepAlive: return ReceiveStatus::kOk;
    case MessageType::kResumed:  // the cache keeps what it holds; updates bring the rest
      if (!cache_->ready() || f.payload_bytes != 4) return ReceiveStatus::kBadMessage;
      has_update_end_ = false;
      return ReceiveStatus::kOk;
    case MessageType::kClose:
    case MessageType::kError: {
      if (!parse_fault(f.payload, f.payload_bytes, &fault_)) return ReceiveStatus::kBadMessage;
      return ReceiveStatus::kClosed;
    }
    default: return ReceiveStatus::kBadMessage;  // a client -> server message
  }
}

ReceiveStatus StreamReceiver::apply_coded(const Frame& f) {
  CodedBatchReader b;
  if (!coded_ || !b.init(code_, f.payload, f.payload_bytes, cache_->header().node_count) ||
      b.count() > part_capacity_ - part_count_)
    return ReceiveStatus::kBadMessage;
  // The part's ids and this batch's merge as they come: the ids so far lie
  // at the end of the storage, and the merged list is written `count`
  // places before them, never overtaking what it reads.
  uint32_t* old = part_ids_ + (part_capacity_ - part_count_);
  uint32_t* const old_end = part_ids_ + part_capacity_;
  uint32_t* const first = old - b.count();
  uint32_t* merged = first;
  const auto merge_below = [&](uint32_t id) {  // the part's ids below id, into the merged list
    while (old < old_end && *old < id) *merged++ = *old++;
  };
  const auto take = [&](uint32_t id) {  // false: the part brought it before
    merge_below(id);
    if (old < old_end && *old == id) return false;
    *merged++ = id;
    return true;
  };
  const auto put = [&](uint32_t id, const NodeFields& fields, uint8_t points) {
    uint8_t record[kMaxRecordBytes];
    pack_record(code_.layout, fields, record);
    return cache_->put(NodeId{id}, record, cache_->record_bytes(), points);
  };
  // Applied entry by entry as they are decoded: a batch that fails part
  // way has put only whole, valid nodes, and the stream stops there.
  while (b.done() < b.count()) {
    CodedBatchReader::Entry e;
    if (!b.next(&e)) return ReceiveStatus::kBadMessage;
    CacheStatus s = CacheStatus::kOk;
    if (e.kind == 0) {
      merge_below(e.id);
      const uint32_t reference_id =
          coded_reference(e.id, merged > first ? merged[-1] : 0xFFFFFFFFu, old < old_end ? *old : 0xFFFFFFFFu);
      NodeFields reference{}, fields;
      if ((reference_id != 0xFFFFFFFFu && !cache_->fields_of(NodeId{reference_id}, &reference)) ||
          !b.node(reference, reference_id == e.id - 1u || reference_id == e.id + 1u, &fields) || !take(e.id))
        return ReceiveStatus::kBadMessage;
      s = put(e.id, fields, e.points);
    } else {
      // A split: the parent the client holds, then its two children.
      NodeFields parent, one, two;
      uint8_t parent_points = 0, second_points = 0;
      if (!cache_->fields_of(NodeId{e.parent}, &parent, &parent_points) ||
          !b.split(parent, parent_points, &one, &two, &second_points) || !take(e.id) || !take(e.id + 1))
        return ReceiveStatus::kBadMessage;
      s = put(e.id, one, e.points);
      if (s == CacheStatus::kOk) s = put(e.id + 1, two, second_points);
    }
    if (s != CacheStatus::kOk) {
      cache_status_ = s;
      return ReceiveStatus::kCacheRefused;
    }
  }
  if (!b.finish()) return ReceiveStatus::kBadMessage;
  part_count_ += b.count();
  nodes_ += b.count();
  part_nodes_ += b.count();
  return ReceiveStatus::kOk;
}

ReceiveStatus StreamReceiver::receive(const uint8_t* data, size_t size) {
  size_t at = 0;
  while (status_ == ReceiveStatus::kOk) {
    at += reader_.feed(data + at, size - at);
    Frame f;
    FrameStatus s;
    while (status_ == ReceiveStatus::kOk && (s = reader_.next(&f)) == FrameStatus::kOk) {
      status_ = apply(f);
      if (status_ != ReceiveStatus::kOk) {
        fault_type_ = static_cast<uint8_t>(f.type);
        fault_sequence_ = f.sequence;
      }
    }
    if (status_ != ReceiveStatus::kOk) break;
    if (s != FrameStatus::kNeedMore) {
      frame_status_ = s;
      status_ = ReceiveStatus::kBadFrame;
      break;
    }
    if (at == size) break;
  }
  bytes_ += size;
  return status_;
}

}  // namespace stipple
