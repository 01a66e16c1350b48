// stipple core — the two ends of a node stream. See stream.h and docs/protocol.md.
#include "core/stream.h"

#include "core/arena.h"

#include "core/spg_writer.h"

namespace stipple {
namespace {

bool is_normal_field(int f) { return f >= static_cast<int>(Field::kFnTheta) && f <= static_cast<int>(Field::kSigmaN); }
bool is_color_field(int f) { return f >= static_cast<int>(Field::kColorR); }

}  // namespace

SpgHeader reduced_header(const SpgHeader& full, uint8_t attributes) {
  SpgHeader h = full;
  const bool normals = full.has_normals() && (attributes & kWantNormals);
  const bool color = full.has_color() && (attributes & kWantColor);
  h.flags = static_cast<uint16_t>((normals ? kAttrNormals : 0) | (color ? kAttrColor : 0));
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

size_t write_reduced_startup(const SpgView& view, uint8_t attributes, uint8_t* out, size_t capacity) {
  const SpgHeader h = reduced_header(view.header, attributes);
  size_t written = 0;
  if (spg_write_startup_le(h, view.sigma_p, h.class_count[1] ? view.sigma_n : nullptr,
                           h.class_count[2] ? view.sigma_c : nullptr, out, capacity, &written) != SpgWriteStatus::kOk)
    return 0;
  return written;
}

size_t SenderScratch::bytes(uint32_t cut_capacity) {
  return align8(kMaxPayload) + align8(kMaxFrameBytes) + CutScratch::bytes(cut_capacity);
}

void SenderScratch::init(void* storage, size_t size) {
  uint8_t* base = static_cast<uint8_t*>(storage);
  const size_t fixed = align8(kMaxPayload) + align8(kMaxFrameBytes);
  payload = size < fixed ? nullptr : base;
  frame = size < fixed ? nullptr : base + align8(kMaxPayload);
  cut.init(base + fixed, size < fixed ? 0 : size - fixed);
}

size_t StreamSender::storage_bytes(const SpgHeader& header) {
  return view_cut_state_bytes(header.node_count) + SenderScratch::bytes(header.node_count);
}

bool StreamSender::init(const SpgView& view, const CutBounds& bounds, void* storage, size_t bytes) {
  if (bytes < storage_bytes(view.header)) return false;
  const size_t state_bytes = view_cut_state_bytes(view.header.node_count);
  own_scratch_.init(static_cast<uint8_t*>(storage) + state_bytes, bytes - state_bytes);
  return init(view, bounds, storage, state_bytes, &own_scratch_);
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
  return attributes;
}

bool StreamSender::start(const Hello& hello, FrameSink sink, void* context) {
  if (view_ == nullptr || hello.version < kOldestProtocolVersion || hello.version > kProtocolVersion) return false;
  const uint8_t attributes = adopt_hello(hello);
  cut_.reset();  // a fresh client: its cut starts empty, so the first update sends it all
  uint8_t* payload = scratch_->payload;
  const size_t n = write_reduced_startup(*view_, attributes, payload, kMaxPayload);
  if (n == 0) return false;
  started_ = true;
  sequence_ = 0;  // a new stream (a serial client says hello again to resynchronise)
  return send(MessageType::kStartup, payload, n, sink, context);
}

uint32_t StreamSender::model_tag(uint8_t attributes) const {
  if (view_ == nullptr || scratch_ == nullptr) return 0;
  const size_t n = write_reduced_startup(*view_, static_cast<uint8_t>(attributes & ~kResuming), scratch_->payload, kMaxPayload);
  return n == 0 ? 0 : crc32(scratch_->payload, n);
}

bool StreamSender::resume(const Hello& hello, const NodeId* held, uint32_t count, FrameSink sink, void* context) {
  if (view_ == nullptr || scratch_ == nullptr || hello.version < 3) return false;
  (void)adopt_hello(hello);
  if (!cut_.adopt_sent(held, count)) return false;
  started_ = true;
  sequence_ = 0;
  uint8_t payload[4];
  store_u32le(payload, count);
  return send(MessageType::kResumed, payload, 4, sink, context);
}

bool StreamSender::update(const CameraUpdate& camera, bool cull, FrameSink sink, void* context) {
  if (!started_) return false;
  CutParams p;
  p.max_size_q4 = camera.max_size_q4;
  p.max_nodes = capacity_;
  p.cull_frustum = p.cull_backfaces = cull;
  for (int k = 0; k < 4; ++k) p.window[k] = camera.window[k];
  cut_status_ = cut_.update(camera.camera, p);
  if (cut_status_ != CutStatus::kOk) return false;
  uint8_t* payload = scratch_->payload;
  // Drops first, so a full client cache makes room before new nodes arrive.
  for (uint32_t done = 0; done < cut_.left_count();) {
    const uint32_t n = cut_.left_count() - done < kDropsPerFrame ? cut_.left_count() - done : kDropsPerFrame;
    store_u32le(payload, n);
    for (uint32_t i = 0; i < n; ++i) store_u32le(payload + 4 + 4 * size_t{i}, index_of(cut_.left()[done + i]));
    if (!send(MessageType::kDrop, payload, 4 + 4 * size_t{n}, sink, context)) return false;
    done += n;
  }
  // Batches of at most kNodeBatchBytes, coarse nodes first (ids are
  // breadth-first): on a slow link the first arrive soon after the startup.
  const size_t stride = node_entry_bytes(reduced_record_bytes_);
  const uint32_t per_frame = static_cast<uint32_t>((kNodeBatchBytes - 4) / stride);
  for (uint32_t done = 0; done < cut_.entered_count();) {
    const uint32_t n = cut_.entered_count() - done < per_frame ? cut_.entered_count() - done : per_frame;
    store_u32le(payload, n);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t id = index_of(cut_.entered()[done + i]);
      uint8_t* entry = payload + 4 + size_t{i} * stride;
      store_u32le(entry, id);
      entry[4] = cut_.points(NodeId{id});
      const uint8_t* record = view_->records + size_t{id} * view_->record_bytes;
      if (same_layout_)
        for (size_t b = 0; b < reduced_record_bytes_; ++b) entry[5 + b] = record[b];
      else
        transcode_record(view_->header.layout, reduced_.layout, record, entry + 5);
    }
    if (!send(MessageType::kNodes, payload, 4 + size_t{n} * stride, sink, context)) return false;
    done += n;
  }
  const UpdateEnd end{camera.sequence, cut_.sent_count()};
  uint8_t buf[kUpdateEndBytes];
  write_update_end(end, buf);
  return send(MessageType::kUpdateEnd, buf, kUpdateEndBytes, sink, context);
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
      has_update_end_ = false;
      return ReceiveStatus::kOk;
    }
    case MessageType::kNodes: {
      NodeBatch b;
      if (!cache_->ready() ||
          !parse_nodes(f.payload, f.payload_bytes, cache_->record_bytes(), cache_->header().node_count, &b))
        return ReceiveStatus::kBadMessage;
      for (uint32_t i = 0; i < b.count; ++i) {
        const CacheStatus s = cache_->put(b.id(i), b.record(i), b.record_bytes, b.points(i));
        if (s != CacheStatus::kOk) return refused(s);
      }
      nodes_ += b.count;
      return ReceiveStatus::kOk;
    }
    case MessageType::kDrop: {
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

ReceiveStatus StreamReceiver::receive(const uint8_t* data, size_t size) {
  size_t at = 0;
  while (status_ == ReceiveStatus::kOk) {
    at += reader_.feed(data + at, size - at);
    Frame f;
    FrameStatus s;
    while (status_ == ReceiveStatus::kOk && (s = reader_.next(&f)) == FrameStatus::kOk) status_ = apply(f);
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
