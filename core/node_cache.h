// stipple core — the node cache: the receiving side of a node stream.
//
// It adopts a startup message (the .spg's header and class tables,
// docs/format.md §1-§2) and then holds node records by id: put (add or
// replace), drop, lookup, and dense iteration for whoever draws them — the
// software point renderer (raster/point_renderer.h) or the GPU client. The
// protocol's node-enter and node-leave messages are put and drop.
//
//   size_t n = node_cache_bytes(limits);   // 0: invalid limits
//   cache.init(limits, storage, n);        // carves the tables from storage
//   cache.load_startup(msg, size);         // forgets every node
//   cache.put(NodeId{7}, record, size);    // validated, then cached
//   cache.drop(NodeId{7});
//
// After init nothing is allocated, nothing is thrown and no floating point
// is used. A record is validated when it is put (class indices against the
// startup's tables, padding bits zero), so every held record decodes. Records
// are kept packed (9-17 bytes a node, unpacked by whoever reads them) or, with
// `decoded`, unpacked once into their fields (NodeFields, 36 bytes), which
// trades memory for the per-frame unpacking. Ids hash into an open-addressed table (linear
// probing, backward-shift deletion; 16-bit entries up to 65,535 nodes); slots stay dense, so iteration visits
// exactly count() records. Not thread-safe: one owner.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/node_decoder.h"
#include "core/node_format.h"
#include "core/spg_format.h"

namespace stipple {

struct NodeCacheLimits {
  uint32_t node_capacity = 30000;          // nodes held at once (1 .. 2^24)
  bool decoded = false;                    // keep unpacked fields (NodeFields) instead of packed records
  bool normals = true, color = true;       // attributes a startup may carry
  uint16_t max_classes[3] = {4096, 4096, 64};  // sigma_p, sigma_n, sigma_c tables
  uint8_t max_angle_bits = 10;             // widest angle field accepted
  uint8_t max_record_bytes = 0;            // widest record held packed; 0: the paper's layout (13 or 17 bytes)
};

enum class CacheStatus : uint8_t {
  kOk = 0,
  kBadLimits,         // init: a limit out of range
  kStorageTooSmall,   // init: fewer bytes than node_cache_bytes
  kNoStartup,         // put/drop before a startup message
  kBadStartup,        // load_startup: the message fails validation (see startup_error)
  kStartupTooLarge,   // load_startup: attributes, class tables or angle widths beyond the limits
  kBadRecordSize,     // put: size differs from the startup's record size
  kBadRecord,         // put: class index beyond its table or nonzero padding
  kFull,              // put: node_capacity nodes already held
  kUnknownNode,       // drop: id not held
  kBadClasses,        // add_class: a class beyond its table, or a bad value
  kClassMissing,      // put: a class the record uses has not come (a model header's cache)
};

const char* cache_status_text(CacheStatus s);

// Storage bytes for the limits (8-byte aligned pieces), or 0 when invalid.
size_t node_cache_bytes(const NodeCacheLimits& limits);

class NodeCache {
 public:
  [[nodiscard]] CacheStatus init(const NodeCacheLimits& limits, void* storage, size_t bytes);

  // Validates and adopts a startup message (spg_parse_startup); forgets
  // every node. What it needs is copied: the caller's buffer may go away.
  [[nodiscard]] CacheStatus load_startup(const uint8_t* data, size_t size);
  // The same from the fixed header alone (.spg §1, protocol version 4):
  // the classes come one by one (add_class) before the nodes that use them;
  // a node whose class has not come is refused (kClassMissing).
  [[nodiscard]] CacheStatus load_model(const uint8_t* data, size_t size);
  // Class `index` of table 0 (sigma_p), 1 (sigma_n) or 2 (sigma_c), its
  // values as in the header's version of .spg §2 (class_value_bytes long).
  [[nodiscard]] CacheStatus add_class(int table, uint32_t index, const uint8_t* values, size_t size);
  size_t class_value_bytes(int table) const { return spg_class_values(table) * spg_class_value_bytes(header_.version); }
  bool class_held(int table, uint32_t index) const;
  uint32_t classes_held(int table) const { return held_count_[table]; }
  // Rises whenever the class tables change (a GPU client re-uploads them).
  uint32_t classes_changed() const { return classes_changed_; }
  SpgResult startup_error() const { return startup_error_; }
  bool ready() const { return ready_; }
  const SpgHeader& header() const { return header_; }
  const NodeDecoder& decoder() const { return decoder_; }
  size_t record_bytes() const { return record_bytes_; }

  // `points`: the original points under the node (saturated at 255; 0 when
  // unknown), what the renderer caps a node's points by (docs/results.md).
  [[nodiscard]] CacheStatus put(NodeId id, const uint8_t* record, size_t size, uint8_t points = 0);
  [[nodiscard]] CacheStatus drop(NodeId id);
  bool has(NodeId id) const;
  // The held node's record fields (and its points byte); false when it is not held.
  [[nodiscard]] bool fields_of(NodeId id, NodeFields* out, uint8_t* points = nullptr) const;
  uint32_t count() const { return count_; }
  // Forgets every node, keeps the startup.
  void clear();

  // Dense iteration, slot 0 .. count() - 1 (order changes on drop).
  NodeId id_at(uint32_t slot) const { return NodeId{ids_[slot]}; }
  uint8_t points_at(uint32_t slot) const { return points_[slot]; }
  // The node in slot `slot`, decoded into *out; false only if its record
  // fails to decode, which put() rules out.
  [[nodiscard]] bool node_at(uint32_t slot, FixedNode* out) const;
  // The cached record: packed, record_bytes() long (when !decoded()).
  const uint8_t* record_at(uint32_t slot) const { return records_ + slot * record_stride_; }
  // Bytes from one slot's record (or fields) to the next's.
  size_t record_stride() const { return record_stride_; }
  // The cached fields, without a copy (when decoded()).
  const NodeFields& fields_at(uint32_t slot) const { return *reinterpret_cast<const NodeFields*>(record_at(slot)); }
  bool decoded() const { return limits_.decoded; }

 private:
  CacheStatus load(const uint8_t* data, size_t size, bool tables);  // a startup, or (without tables) a header
  CacheStatus adopt(const SpgView& view);  // a parsed startup or header
  uint32_t find(uint32_t id) const;  // id's hash entry, or the empty one ending its probe sequence
  uint32_t home_slot(uint32_t id) const;  // where id's probe sequence starts
  void erase_hash(uint32_t at);
  uint32_t entry(uint32_t i) const { return hash16_ != nullptr ? hash16_[i] : hash32_[i]; }
  void set_entry(uint32_t i, uint32_t v) {
    if (hash16_ != nullptr) hash16_[i] = static_cast<uint16_t>(v);
    else hash32_[i] = v;
  }

  NodeCacheLimits limits_{};
  NodeDecoder decoder_;
  bool ready_ = false;
  SpgResult startup_error_{};
  SpgHeader header_{};
  size_t record_bytes_ = 0, record_stride_ = 0, decoder_bytes_ = 0;
  void* decoder_storage_ = nullptr;
  uint8_t* records_ = nullptr;  // node_capacity x record_stride_
  uint32_t* ids_ = nullptr;     // per slot
  uint8_t* points_ = nullptr;   // per slot: original points, saturated at 255
  // Slot + 1, 0 = empty; linear probing. 16-bit entries where the
  // capacity allows (node_capacity < 2^16), else 32-bit: one of the two.
  uint16_t* hash16_ = nullptr;
  uint32_t* hash32_ = nullptr;
  uint32_t hash_mask_ = 0;
  uint32_t count_ = 0;
  uint32_t classes_changed_ = 0;
  uint8_t* held_ = nullptr;  // a bit a class, tables one after another (without all_held_)
  bool all_held_ = false;
  uint32_t held_count_[3] = {};
};

}  // namespace stipple
