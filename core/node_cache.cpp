// stipple core — the node cache. See node_cache.h.
#include "core/node_cache.h"

#include "core/arena.h"

#include <initializer_list>

namespace stipple {
namespace {

struct Layout {
  size_t decoder, records, ids, points, hash, total;
  size_t decoder_bytes, record_stride;
  uint32_t hash_entries;
  size_t held;  // one bit a class a startup may have: which have come
};

// A hash entry holds a slot + 1 (0: empty): 16 bits where every slot's
// fits, as at the handheld's 30 K nodes (128 KB of its 2 MiB arena).
size_t hash_entry_bytes(const NodeCacheLimits& l) { return l.node_capacity <= 0xFFFFu ? 2 : 4; }

bool valid(const NodeCacheLimits& l) {
  return l.node_capacity >= 1 && l.node_capacity <= (1u << 24) && l.max_angle_bits >= 1 &&
         l.max_angle_bits <= kMaxAngleBits && l.max_classes[0] >= 1 && l.max_record_bytes <= kMaxRecordBytes;
}

// The largest startup the limits accept: every angle field at
// max_angle_bits, every class table full.
SpgHeader worst_header(const NodeCacheLimits& c) {
  SpgHeader h;
  h.flags = static_cast<uint16_t>((c.normals ? kAttrNormals : 0) | (c.color ? kAttrColor : 0));
  h.layout = paper_layout(c.normals, c.color, 2);
  for (Field theta : {Field::kFpTheta, Field::kFnTheta, Field::kFcTheta})
    for (int k = 0; k < 3; ++k)
      if (h.layout.bits[static_cast<int>(theta) + k] > 0) h.layout.bits[static_cast<int>(theta) + k] = c.max_angle_bits;
  h.class_count[0] = c.max_classes[0];
  h.class_count[1] = c.normals ? c.max_classes[1] : 0;
  h.class_count[2] = c.color ? c.max_classes[2] : 0;
  return h;
}

Layout layout_of(const NodeCacheLimits& c) {
  Layout l{};
  l.decoder_bytes = node_decoder_bytes(worst_header(c));
  const size_t paper = static_cast<size_t>(paper_layout(c.normals, c.color, 2).record_bytes());
  l.record_stride = c.decoded ? sizeof(NodeFields) : c.max_record_bytes > paper ? size_t{c.max_record_bytes} : paper;
  l.hash_entries = 1;
  while (l.hash_entries < c.node_capacity + c.node_capacity / 2) l.hash_entries <<= 1;
  ArenaCarver arena;
  const auto take = [&](size_t bytes) { return arena.take(bytes); };
  l.decoder = take(l.decoder_bytes);
  l.records = take(l.record_stride * c.node_capacity);
  l.ids = take(4 * size_t{c.node_capacity});
  l.points = take(size_t{c.node_capacity});
  l.hash = take(hash_entry_bytes(c) * size_t{l.hash_entries});
  l.held = take((size_t{c.max_classes[0]} + c.max_classes[1] + c.max_classes[2] + 7) / 8);
  l.total = arena.total();
  return l;
}

inline uint32_t hash_of(uint32_t id) { return id * 2654435761u; }

}  // namespace

const char* cache_status_text(CacheStatus s) {
  switch (s) {
    case CacheStatus::kOk: return "ok";
    case CacheStatus::kBadLimits: return "invalid node cache limits";
    case CacheStatus::kStorageTooSmall: return "storage smaller than node_cache_bytes";
    case CacheStatus::kNoStartup: return "no startup message loaded";
    case CacheStatus::kBadStartup: return "startup message is invalid";
    case CacheStatus::kStartupTooLarge: return "startup message needs more than the cache was configured for";
    case CacheStatus::kBadRecordSize: return "node record size differs from the startup message's";
    case CacheStatus::kBadRecord: return "node record has a class index beyond its table or nonzero padding";
    case CacheStatus::kFull: return "node cache is full";
    case CacheStatus::kBadClasses: return "a class beyond its table, or a bad class value";
    case CacheStatus::kClassMissing: return "node record uses a class that has not come yet";
    case CacheStatus::kUnknownNode: return "node is not in the cache";
  }
  return "unknown status";
}

size_t node_cache_bytes(const NodeCacheLimits& limits) { return valid(limits) ? layout_of(limits).total : 0; }

CacheStatus NodeCache::init(const NodeCacheLimits& limits, void* storage, size_t bytes) {
  if (!valid(limits)) return CacheStatus::kBadLimits;
  const Layout l = layout_of(limits);
  if (bytes < l.total) return CacheStatus::kStorageTooSmall;
  uint8_t* base = static_cast<uint8_t*>(storage);
  limits_ = limits;
  decoder_storage_ = base + l.decoder;
  decoder_bytes_ = l.decoder_bytes;
  record_stride_ = l.record_stride;
  records_ = base + l.records;
  ids_ = reinterpret_cast<uint32_t*>(base + l.ids);
  points_ = base + l.points;
  hash16_ = hash_entry_bytes(limits) == 2 ? reinterpret_cast<uint16_t*>(base + l.hash) : nullptr;
  hash32_ = hash16_ == nullptr ? reinterpret_cast<uint32_t*>(base + l.hash) : nullptr;
  hash_mask_ = l.hash_entries - 1;
  held_ = base + l.held;
  ready_ = false;
  clear();
  return CacheStatus::kOk;
}

void NodeCache::clear() {
  count_ = 0;
  for (uint32_t i = 0; i <= hash_mask_; ++i) set_entry(i, 0);
}

CacheStatus NodeCache::load_startup(const uint8_t* data, size_t size) { return load(data, size, true); }

CacheStatus NodeCache::load_model(const uint8_t* data, size_t size) { return load(data, size, false); }

CacheStatus NodeCache::load(const uint8_t* data, size_t size, bool tables) {
  if (records_ == nullptr) return CacheStatus::kBadLimits;
  ready_ = false;
  clear();
  SpgView view;
  size_t used = 0;
  // Without tables (a model header): the decoder holds no class yet.
  startup_error_ = tables ? spg_parse_startup(data, size, &view, &used) : spg_parse_header(data, size, &view.header, &used);
  if (!startup_error_.ok()) return CacheStatus::kBadStartup;
  return adopt(view);
}

CacheStatus NodeCache::adopt(const SpgView& view) {
  const SpgHeader& h = view.header;
  if ((h.has_normals() && !limits_.normals) || (h.has_color() && !limits_.color)) return CacheStatus::kStartupTooLarge;
  for (int c = 0; c < 3; ++c)
    if (h.class_count[c] > limits_.max_classes[c]) return CacheStatus::kStartupTooLarge;
  if ((!limits_.decoded && static_cast<size_t>(h.layout.record_bytes()) > record_stride_) ||
      node_decoder_bytes(h) > decoder_bytes_)
    return CacheStatus::kStartupTooLarge;
  for (Field theta : {Field::kFpTheta, Field::kFnTheta, Field::kFcTheta})
    for (int k = 0; k < 3; ++k)
      if (h.layout.bits[static_cast<int>(theta) + k] > limits_.max_angle_bits) return CacheStatus::kStartupTooLarge;
  if (decoder_.init(view, decoder_storage_, decoder_bytes_) != DecodeStatus::kOk) return CacheStatus::kStartupTooLarge;
  header_ = h;
  record_bytes_ = static_cast<size_t>(h.layout.record_bytes());
  // Every class held (a whole startup), or none yet (a model header).
  all_held_ = view.sigma_p != nullptr;
  for (int t = 0; t < 3; ++t) held_count_[t] = all_held_ ? h.class_count[t] : 0;
  const size_t bits = size_t{h.class_count[0]} + h.class_count[1] + h.class_count[2];
  for (size_t i = 0; i < (bits + 7) / 8 && !all_held_; ++i) held_[i] = 0;
  ++classes_changed_;
  ready_ = true;
  return CacheStatus::kOk;
}

bool NodeCache::class_held(int table, uint32_t index) const {
  if (all_held_) return true;
  const size_t bit = spg_class_bit(header_, table, index);
  return (held_[bit / 8] >> (bit % 8)) & 1u;
}

CacheStatus NodeCache::add_class(int table, uint32_t index, const uint8_t* values, size_t size) {
  if (!ready_) return CacheStatus::kNoStartup;
  if (table < 0 || table > 2 || index >= header_.class_count[table] || size != class_value_bytes(table) ||
      !spg_check_class_values(header_.version, values, size).ok())
    return CacheStatus::kBadClasses;
  if (!decoder_.set_classes(table, index, 1, values)) return CacheStatus::kBadClasses;
  if (!class_held(table, index)) {
    const size_t bit = spg_class_bit(header_, table, index);
    held_[bit / 8] = static_cast<uint8_t>(held_[bit / 8] | (1u << (bit % 8)));
    ++held_count_[table];
  }
  ++classes_changed_;
  return CacheStatus::kOk;
}

uint32_t NodeCache::home_slot(uint32_t id) const {
  const int shift = 32 - __builtin_popcount(hash_mask_);  // the table has hash_mask_ + 1 = 2^k entries
  return shift >= 32 ? 0 : hash_of(id) >> shift;
}

uint32_t NodeCache::find(uint32_t id) const {
  for (uint32_t i = home_slot(id);; i = (i + 1) & hash_mask_) {
    const uint32_t e = entry(i);
    if (e == 0 || ids_[e - 1] == id) return i;
  }
}

bool NodeCache::has(NodeId id) const { return ready_ && entry(find(index_of(id))) != 0; }

bool NodeCache::fields_of(NodeId id, NodeFields* out, uint8_t* points) const {
  if (!ready_) return false;
  const uint32_t e = entry(find(index_of(id)));
  if (e == 0) return false;
  *out = decoded() ? fields_at(e - 1) : unpack_record(header_.layout, record_at(e - 1));
  if (points != nullptr) *points = points_[e - 1];
  return true;
}

void NodeCache::erase_hash(uint32_t hole) {
  // Backward-shift deletion keeps every probe sequence unbroken.
  for (uint32_t j = (hole + 1) & hash_mask_; entry(j) != 0; j = (j + 1) & hash_mask_) {
    const uint32_t home = home_slot(ids_[entry(j) - 1]);
    // Move j into the hole unless its home lies cyclically in (hole, j].
    const bool stays = hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
    if (!stays) {
      set_entry(hole, entry(j));
      hole = j;
    }
  }
  set_entry(hole, 0);
}

CacheStatus NodeCache::put(NodeId node, const uint8_t* record, size_t size, uint8_t points) {
  if (!ready_) return CacheStatus::kNoStartup;
  if (size != record_bytes_) return CacheStatus::kBadRecordSize;
  const int pad_bits = static_cast<int>(record_bytes_ * 8) - header_.layout.total_bits();
  if (pad_bits > 0 && (record[record_bytes_ - 1] >> (8 - pad_bits)) != 0) return CacheStatus::kBadRecord;
  const NodeFields fields = decoder_.unpacker().unpack(record);
  if (!decoder_.classes_valid(fields)) return CacheStatus::kBadRecord;
  if (!all_held_ && (!class_held(0, fields[Field::kSigmaP]) || (header_.has_normals() && !class_held(1, fields[Field::kSigmaN])) ||
                     (header_.has_color() && !class_held(2, fields[Field::kSigmaC]))))
    return CacheStatus::kClassMissing;
  const uint32_t id = index_of(node);
  const uint32_t at = find(id);
  uint32_t slot;
  if (entry(at) != 0) {
    slot = entry(at) - 1;
  } else {
    if (count_ >= limits_.node_capacity) return CacheStatus::kFull;
    slot = count_++;
    ids_[slot] = id;
    set_entry(at, slot + 1);
  }
  uint8_t* dst = records_ + slot * record_stride_;
  if (limits_.decoded) *reinterpret_cast<NodeFields*>(dst) = fields;
  else
    for (size_t i = 0; i < record_bytes_; ++i) dst[i] = record[i];
  points_[slot] = points;
  return CacheStatus::kOk;
}

CacheStatus NodeCache::drop(NodeId node) {
  if (!ready_) return CacheStatus::kNoStartup;
  const uint32_t at = find(index_of(node));
  if (entry(at) == 0) return CacheStatus::kUnknownNode;
  const uint32_t slot = entry(at) - 1, last = count_ - 1;
  erase_hash(at);
  if (slot != last) {  // keep the cache dense: the last node moves into the hole
    const uint8_t* src = records_ + last * record_stride_;
    uint8_t* dst = records_ + slot * record_stride_;
    for (size_t i = 0; i < record_stride_; ++i) dst[i] = src[i];
    ids_[slot] = ids_[last];
    points_[slot] = points_[last];
    set_entry(find(ids_[slot]), slot + 1);
  }
  --count_;
  return CacheStatus::kOk;
}

bool NodeCache::node_at(uint32_t slot, FixedNode* out) const {
  if (limits_.decoded) return decoder_.decode(fields_at(slot), out) == DecodeStatus::kOk;
  return decoder_.decode(record_at(slot), out) == DecodeStatus::kOk;
}

}  // namespace stipple
