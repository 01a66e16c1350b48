// stipple core — the node stream's protocol. See protocol.h and docs/protocol.md.
#include "core/protocol.h"

#include "core/spg_format.h"
#include "core/spg_writer.h"

namespace stipple {
namespace {

inline int32_t load_i32le(const uint8_t* p) { return static_cast<int32_t>(load_u32le(p)); }
inline void store_i32le(uint8_t* p, int32_t v) { store_u32le(p, static_cast<uint32_t>(v)); }

}  // namespace

bool message_type_known(uint8_t t) {
  switch (static_cast<MessageType>(t)) {
    case MessageType::kHello:
    case MessageType::kCamera:
    case MessageType::kKeepAlive:
    case MessageType::kClose:
    case MessageType::kAck:
    case MessageType::kResend:
    case MessageType::kResume:
    case MessageType::kResumed:
    case MessageType::kModel:
    case MessageType::kClasses:
    case MessageType::kUpdateBegin:
    case MessageType::kCode:
    case MessageType::kCodedNodes:
    case MessageType::kCodedClasses:
    case MessageType::kStartup:
    case MessageType::kNodes:
    case MessageType::kDrop:
    case MessageType::kUpdateEnd:
    case MessageType::kError: return true;
  }
  return false;
}

const char* message_type_name(uint8_t t) {
  switch (static_cast<MessageType>(t)) {
    case MessageType::kHello: return "hello";
    case MessageType::kCamera: return "camera";
    case MessageType::kKeepAlive: return "keep-alive";
    case MessageType::kClose: return "close";
    case MessageType::kAck: return "ack";
    case MessageType::kResend: return "resend";
    case MessageType::kResume: return "resume";
    case MessageType::kResumed: return "resumed";
    case MessageType::kModel: return "model";
    case MessageType::kClasses: return "classes";
    case MessageType::kUpdateBegin: return "update-begin";
    case MessageType::kCode: return "code";
    case MessageType::kCodedNodes: return "coded nodes";
    case MessageType::kCodedClasses: return "coded classes";
    case MessageType::kStartup: return "startup";
    case MessageType::kNodes: return "nodes";
    case MessageType::kDrop: return "drop";
    case MessageType::kUpdateEnd: return "update-end";
    case MessageType::kError: return "error";
  }
  return "unknown";
}

const char* frame_status_text(FrameStatus s) {
  switch (s) {
    case FrameStatus::kOk: return "ok";
    case FrameStatus::kNeedMore: return "incomplete frame";
    case FrameStatus::kBadFlags: return "frame flags are not zero";
    case FrameStatus::kUnknownType: return "unknown message type";
    case FrameStatus::kOversized: return "frame longer than the limit";
    case FrameStatus::kBadChecksum: return "frame CRC-32 mismatch";
    case FrameStatus::kOutOfSequence: return "frame out of sequence";
    case FrameStatus::kBadPayload: return "message payload is malformed";
    case FrameStatus::kTruncated: return "stream ended inside a frame";
  }
  return "unknown status";
}

const char* close_reason_text(CloseReason r) {
  switch (r) {
    case CloseReason::kNormal: return "closed";
    case CloseReason::kBadFrame: return "a frame was refused";
    case CloseReason::kBadHello: return "the hello was refused";
    case CloseReason::kUnsupported: return "protocol version not supported";
    case CloseReason::kServerFull: return "the server has no room for another client";
    case CloseReason::kShutdown: return "the server is shutting down";
    case CloseReason::kTimeout: return "nothing arrived in time (no hello, or an idle client)";
    case CloseReason::kBadToken: return "the server needs the right token (--token)";
    case CloseReason::kBadResume: return "the resume was refused";
  }
  return "unknown reason";
}

size_t write_frame(MessageType type, uint16_t sequence, const uint8_t* payload, size_t payload_bytes, uint8_t* out,
                   size_t capacity) {
  if (payload_bytes > kMaxPayload || capacity < kFrameHeaderBytes + payload_bytes + kFrameTrailerBytes) return 0;
  out[0] = static_cast<uint8_t>(type);
  out[1] = 0;
  store_u16le(out + 2, sequence);
  store_u32le(out + 4, static_cast<uint32_t>(payload_bytes));
  for (size_t i = 0; i < payload_bytes; ++i) out[kFrameHeaderBytes + i] = payload[i];
  const size_t body = kFrameHeaderBytes + payload_bytes;
  store_u32le(out + body, crc32(out, body));
  return body + kFrameTrailerBytes;
}

void FrameReader::init(uint8_t* storage, size_t bytes) {
  buffer_ = storage;
  capacity_ = bytes;
  reset();
}

void FrameReader::reset() {
  used_ = consumed_ = 0;
  expected_ = 0;
  fault_ = FrameStatus::kOk;
}

size_t FrameReader::feed(const uint8_t* data, size_t size) {
  if (fault_ != FrameStatus::kOk || buffer_ == nullptr) return 0;
  if (consumed_ > 0) {  // drop the frames already handed out
    for (size_t i = consumed_; i < used_; ++i) buffer_[i - consumed_] = buffer_[i];
    used_ -= consumed_;
    consumed_ = 0;
  }
  const size_t take = size < capacity_ - used_ ? size : capacity_ - used_;
  for (size_t i = 0; i < take; ++i) buffer_[used_ + i] = data[i];
  used_ += take;
  return take;
}

FrameStatus FrameReader::next(Frame* frame) {
  if (fault_ != FrameStatus::kOk) return fault_;
  const size_t available = used_ - consumed_;
  const uint8_t* p = buffer_ + consumed_;
  if (available < kFrameHeaderBytes) return FrameStatus::kNeedMore;
  // Every header field is checked before the length is trusted.
  const auto fail = [&](FrameStatus s) { return fault_ = s; };
  if (p[1] != 0) return fail(FrameStatus::kBadFlags);
  if (!message_type_known(p[0])) return fail(FrameStatus::kUnknownType);
  const uint32_t length = load_u32le(p + 4);
  if (length > kMaxPayload || kFrameHeaderBytes + size_t{length} + kFrameTrailerBytes > capacity_)
    return fail(FrameStatus::kOversized);
  const size_t total = kFrameHeaderBytes + length + kFrameTrailerBytes;
  if (available < total) return FrameStatus::kNeedMore;
  if (load_u32le(p + kFrameHeaderBytes + length) != crc32(p, kFrameHeaderBytes + length))
    return fail(FrameStatus::kBadChecksum);
  const uint16_t sequence = load_u16le(p + 2);
  if (sequence != expected_) return fail(FrameStatus::kOutOfSequence);
  ++expected_;
  frame->type = static_cast<MessageType>(p[0]);
  frame->sequence = sequence;
  frame->payload = p + kFrameHeaderBytes;
  frame->payload_bytes = length;
  consumed_ += total;
  return FrameStatus::kOk;
}

size_t write_hello(const Hello& h, uint8_t out[kHelloMaxBytes]) {
  store_u16le(out, h.version);
  store_u16le(out + 2, h.width);
  store_u16le(out + 4, h.height);
  out[6] = h.pixel_format;
  out[7] = h.attributes;
  store_u32le(out + 8, h.cache_capacity);
  const size_t token = h.token_bytes > kMaxTokenBytes ? kMaxTokenBytes : h.token_bytes;
  for (size_t i = 0; i < token; ++i) out[kHelloBytes + i] = h.token[i];
  return kHelloBytes + token;
}

bool parse_hello(const uint8_t* p, size_t size, Hello* out) {
  if (size < kHelloBytes || size > kHelloMaxBytes) return false;
  Hello h;
  h.version = load_u16le(p);
  h.width = load_u16le(p + 2);
  h.height = load_u16le(p + 4);
  h.pixel_format = p[6];
  h.attributes = p[7];
  h.cache_capacity = load_u32le(p + 8);
  // Version 2 knows neither a token nor a resume; before 5 no batch is
  // coded, before 7 no class is signed.
  const uint8_t known = static_cast<uint8_t>(kWantNormals | kWantColor | (h.version >= 3 ? kResuming : 0) |
                                             (h.version >= 5 ? kWantCoded : 0) | (h.version >= 7 ? kWantCurvatureSign : 0));
  if (h.width == 0 || h.width > 4096 || h.height == 0 || h.height > 4096 || h.pixel_format > 1 ||
      (h.attributes & ~known) != 0 || h.cache_capacity == 0 || h.cache_capacity > (1u << 24) ||
      (h.version < 3 && size != kHelloBytes))
    return false;
  h.token_bytes = static_cast<uint8_t>(size - kHelloBytes);
  for (size_t i = 0; i < h.token_bytes; ++i) h.token[i] = p[kHelloBytes + i];
  *out = h;
  return true;
}

bool hello_token_matches(const Hello& h, const uint8_t* token, size_t token_bytes) {
  // Every byte of the longest token is compared, whatever differs first.
  uint32_t diff = static_cast<uint32_t>(h.token_bytes ^ token_bytes);
  for (size_t i = 0; i < kMaxTokenBytes; ++i) {
    const uint8_t a = i < h.token_bytes ? h.token[i] : 0, b = i < token_bytes ? token[i] : 0;
    diff |= static_cast<uint32_t>(a ^ b);
  }
  return diff == 0 && token_bytes <= kMaxTokenBytes;
}

size_t write_resume_part(uint32_t model_tag, const uint32_t* ids, uint32_t count, uint32_t* at, uint32_t* previous,
                         uint8_t* out, size_t capacity) {
  if (capacity < kResumeHeaderBytes + 5) return 0;
  out[1] = out[2] = out[3] = 0;
  store_u32le(out + 4, model_tag);
  store_u32le(out + 8, count);
  size_t n = kResumeHeaderBytes;
  while (*at < count && n + 5 <= capacity) {
    // Wraps from 0xFFFFFFFF: the first id's difference is id + 1.
    n += store_leb128(out + n, ids[*at] - *previous);
    *previous = ids[(*at)++];
  }
  out[0] = *at == count ? 1 : 0;
  return n;
}

bool parse_resume_part(const uint8_t* p, size_t size, ResumePart* out) {
  if (size < kResumeHeaderBytes || (p[0] & ~1u) != 0 || p[1] != 0 || p[2] != 0 || p[3] != 0) return false;
  out->last = p[0] & 1;
  out->model_tag = load_u32le(p + 4);
  out->total = load_u32le(p + 8);
  out->ids = p + kResumeHeaderBytes;
  out->ids_bytes = size - kResumeHeaderBytes;
  return true;
}

ResumeId next_resume_id(const uint8_t** at, const uint8_t* end, uint32_t* previous, uint32_t* id) {
  if (*at >= end) return ResumeId::kEnd;
  uint32_t gap = 0;
  if (!load_leb128(at, end, &gap)) return ResumeId::kMalformed;
  const int64_t before = *previous == 0xFFFFFFFFu ? -1 : int64_t{*previous};
  const int64_t next = before + static_cast<int64_t>(gap);
  if (gap == 0) return ResumeId::kRepeated;
  if (next > 0xFFFFFFFE) return ResumeId::kMalformed;
  *previous = static_cast<uint32_t>(next);
  *id = *previous;
  return ResumeId::kId;
}

size_t write_camera_update(const CameraUpdate& c, uint8_t* out) {
  uint8_t* at = out;
  store_u32le(at, c.sequence);
  at += 4;
  const auto put = [&](int32_t v) {
    store_i32le(at, v);
    at += 4;
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) put(c.camera.rotation[i][j]);
  for (int k = 0; k < 3; ++k) put(c.camera.eye[k]);
  put(c.camera.focal_q4);
  put(c.camera.center_q4[0]);
  put(c.camera.center_q4[1]);
  put(c.camera.near_mu);
  put(c.camera.far_mu);
  put(c.max_size_q4);
  for (int k = 0; k < 4; ++k) put(c.window[k]);
  if (!c.accumulate) return kCameraUpdateBytes;
  store_u32le(at, kCameraAccumulate);
  return kCameraUpdateFlagsBytes;
}

bool parse_camera_update(const uint8_t* p, size_t size, CameraUpdate* out) {
  if (size != kCameraUpdateBytes && size != kCameraUpdateFlagsBytes) return false;
  CameraUpdate c;
  const uint8_t* at = p;
  c.sequence = load_u32le(at);
  at += 4;
  const auto get = [&]() {
    const int32_t v = load_i32le(at);
    at += 4;
    return v;
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c.camera.rotation[i][j] = get();
  for (int k = 0; k < 3; ++k) c.camera.eye[k] = get();
  c.camera.focal_q4 = get();
  c.camera.center_q4[0] = get();
  c.camera.center_q4[1] = get();
  c.camera.near_mu = get();
  c.camera.far_mu = get();
  c.max_size_q4 = get();
  for (int k = 0; k < 4; ++k) c.window[k] = get();
  // The ranges the camera's fixed-point users rely on (core/camera.h).
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (c.camera.rotation[i][j] < -(1 << 14) || c.camera.rotation[i][j] > (1 << 14)) return false;
  for (int k = 0; k < 3; ++k)
    if (c.camera.eye[k] < -(1 << 29) || c.camera.eye[k] > (1 << 29)) return false;
  if (c.camera.focal_q4 < 1 || c.camera.focal_q4 > (1 << 20) || c.camera.near_mu < kCameraMinDistance ||
      c.camera.far_mu <= c.camera.near_mu || c.camera.far_mu > (1 << 30))
    return false;
  for (int k = 0; k < 2; ++k)
    if (c.camera.center_q4[k] < 0 || c.camera.center_q4[k] > 16 * 4096) return false;
  if (c.max_size_q4 < 1 || c.max_size_q4 > 16 * 4096) return false;
  for (int k = 0; k < 4; ++k)
    if (c.window[k] < 0 || c.window[k] > 4096) return false;
  if (size == kCameraUpdateFlagsBytes) {
    const uint32_t flags = load_u32le(at);
    if ((flags & ~kCameraAccumulate) != 0) return false;
    c.accumulate = (flags & kCameraAccumulate) != 0;
  }
  *out = c;
  return true;
}

size_t write_update_end(const UpdateEnd& u, uint8_t out[kUpdateEndBytes]) {
  store_u32le(out, u.camera_sequence);
  store_u32le(out + 4, u.sent_nodes);
  return kUpdateEndBytes;
}

bool parse_update_end(const uint8_t* p, size_t size, UpdateEnd* out) {
  if (size != kUpdateEndBytes) return false;
  out->camera_sequence = load_u32le(p);
  out->sent_nodes = load_u32le(p + 4);
  return true;
}

size_t write_classes_header(uint8_t table, uint16_t count, uint8_t out[kClassesHeaderBytes]) {
  out[0] = table;
  out[1] = 0;
  store_u16le(out + 2, count);
  return kClassesHeaderBytes;
}

bool parse_classes(const uint8_t* p, size_t size, ClassesPiece* out) {
  if (size <= kClassesHeaderBytes || p[0] > 2 || p[1] != 0) return false;
  out->table = p[0];
  out->count = load_u16le(p + 2);
  out->entries = p + kClassesHeaderBytes;
  out->entries_bytes = size - kClassesHeaderBytes;
  return out->count > 0;
}

bool next_class_entry(const uint8_t** at, const uint8_t* end, size_t value_bytes, uint32_t* previous, uint32_t* index,
                      const uint8_t** values) {
  uint32_t id = 0;
  switch (next_resume_id(at, end, previous, &id)) {  // the same ascending LEB128 differences
    case ResumeId::kId: break;
    default: return false;
  }
  if (id > 0xFFFF || static_cast<size_t>(end - *at) < value_bytes) return false;
  *index = id;
  *values = *at;
  *at += value_bytes;
  return true;
}

size_t write_update_begin(const UpdateBegin& u, uint8_t out[kUpdateBeginBytes]) {
  store_u32le(out, u.camera_sequence);
  store_u32le(out + 4, u.entering);
  store_u32le(out + 8, u.leaving);
  out[12] = u.parts_after;
  out[13] = out[14] = out[15] = 0;
  return kUpdateBeginBytes;
}

bool parse_update_begin(const uint8_t* p, size_t size, UpdateBegin* out) {
  if (size != kUpdateBeginBytes || p[13] != 0 || p[14] != 0 || p[15] != 0) return false;
  out->camera_sequence = load_u32le(p);
  out->entering = load_u32le(p + 4);
  out->leaving = load_u32le(p + 8);
  out->parts_after = p[12];
  return true;
}

size_t write_fault(const Fault& f, uint8_t out[kFaultBytes]) {
  out[0] = static_cast<uint8_t>(f.reason);
  out[1] = static_cast<uint8_t>(f.status);
  store_u16le(out + 2, f.sequence);
  return kFaultBytes;
}

bool parse_fault(const uint8_t* p, size_t size, Fault* out) {
  if (size != kFaultBytes || p[0] > static_cast<uint8_t>(CloseReason::kBadResume) ||
      p[1] > static_cast<uint8_t>(FrameStatus::kTruncated))
    return false;
  out->reason = static_cast<CloseReason>(p[0]);
  out->status = static_cast<FrameStatus>(p[1]);
  out->sequence = load_u16le(p + 2);
  return true;
}

size_t write_sequence(uint16_t sequence, uint8_t out[kSequenceBytes]) {
  store_u16le(out, sequence);
  out[2] = out[3] = 0;
  return kSequenceBytes;
}

bool parse_sequence(const uint8_t* p, size_t size, uint16_t* out) {
  if (size != kSequenceBytes || p[2] != 0 || p[3] != 0) return false;
  *out = load_u16le(p);
  return true;
}

NodeId NodeBatch::id(uint32_t i) const { return NodeId{load_u32le(entries + size_t{i} * node_entry_bytes(record_bytes))}; }
NodeId DropBatch::id(uint32_t i) const { return NodeId{load_u32le(ids + size_t{i} * 4)}; }

bool parse_nodes(const uint8_t* p, size_t size, size_t record_bytes, uint32_t node_count, NodeBatch* out) {
  if (size < 4 || record_bytes == 0) return false;
  const uint32_t count = load_u32le(p);
  if (count > nodes_per_frame(record_bytes) || size != 4 + size_t{count} * node_entry_bytes(record_bytes)) return false;
  NodeBatch b;
  b.count = count;
  b.record_bytes = record_bytes;
  b.entries = p + 4;
  for (uint32_t i = 0; i < count; ++i)
    if (index_of(b.id(i)) >= node_count) return false;
  *out = b;
  return true;
}

namespace {

bool parse_compact(const uint8_t* p, size_t size, size_t record_bytes, uint32_t node_count, uint32_t most,
                   CompactBatch* out) {
  if (size < 4) return false;
  CompactBatch b;
  b.count = load_u32le(p);
  b.record_bytes = record_bytes;
  b.at = p + 4;
  b.end = p + size;
  if (b.count > most) return false;
  const uint8_t* at = b.at;
  uint32_t previous = 0xFFFFFFFFu, id = 0;
  const size_t tail = record_bytes == 0 ? 0 : 1 + record_bytes;
  for (uint32_t i = 0; i < b.count; ++i) {
    if (next_resume_id(&at, b.end, &previous, &id) != ResumeId::kId || id >= node_count ||
        static_cast<size_t>(b.end - at) < tail)
      return false;
    at += tail;
  }
  if (at != b.end) return false;
  *out = b;
  return true;
}

}  // namespace

bool parse_compact_nodes(const uint8_t* p, size_t size, size_t record_bytes, uint32_t node_count, CompactBatch* out) {
  return record_bytes > 0 && parse_compact(p, size, record_bytes, node_count, nodes_per_frame(record_bytes), out);
}

bool parse_compact_drop(const uint8_t* p, size_t size, uint32_t node_count, CompactBatch* out) {
  return parse_compact(p, size, 0, node_count, kDropsPerFrame, out);
}

void next_compact(CompactBatch* b, uint32_t* id, uint8_t* points, const uint8_t** record) {
  (void)next_resume_id(&b->at, b->end, &b->previous, id);  // checked by parse_compact_*
  if (b->record_bytes == 0) return;
  *points = *b->at;
  *record = b->at + 1;
  b->at += 1 + b->record_bytes;
}

bool parse_drop(const uint8_t* p, size_t size, uint32_t node_count, DropBatch* out) {
  if (size < 4) return false;
  const uint32_t count = load_u32le(p);
  if (count > kDropsPerFrame || size != 4 + size_t{count} * 4) return false;
  DropBatch b;
  b.count = count;
  b.ids = p + 4;
  for (uint32_t i = 0; i < count; ++i)
    if (index_of(b.id(i)) >= node_count) return false;
  *out = b;
  return true;
}

}  // namespace stipple
