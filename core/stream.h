// stipple core — the two ends of a node stream, over core/protocol frames.
//
// Server side, per client (StreamSender): the startup message reduced to the
// attributes the client asked for (a grey screen gets no colour, a client
// without lighting no normals — smaller records), and, per camera update,
// the change of the client's view-dependent cut (core/view_cut.h) as drop
// and node batches with each record transcoded to the reduced layout, then
// an update-end marker. Client side (StreamReceiver): frames applied to a
// NodeCache — startup adopted, nodes put, drops dropped — with every id and
// length checked, and the converged state reported.
//
// Both are integer-only and allocation-free over caller storage; neither
// touches a socket: bytes go to and come from a transport (platform/).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/node_cache.h"
#include "core/node_coding.h"
#include "core/protocol.h"
#include "core/spg_format.h"
#include "core/view_cut.h"

namespace stipple {

// The header a client asking for `attributes` (kWantNormals | kWantColor)
// receives: attributes the model lacks or the client does not want are
// removed from the flags, the layout and the class counts.
SpgHeader reduced_header(const SpgHeader& full, uint8_t attributes);

// A record of layout `from` in layout `to` (the same fields minus the removed
// attributes: their fields are dropped, the others keep their values).
void transcode_record(const RecordLayout& from, const RecordLayout& to, const uint8_t* in, uint8_t* out);

// Writes the reduced startup message (header and the wanted class tables)
// into out[0 .. capacity); returns its length or 0 when it does not fit.
size_t write_reduced_startup(const SpgView& view, uint8_t attributes, uint8_t* out, size_t capacity);

// Where a sender's frames go: called with each whole frame (a transport's
// write, a queue); false stops the update (the link is gone).
using FrameSink = bool (*)(void* context, const uint8_t* frame, size_t size);

// The coded batches' tables (protocol 5) of one model, per attribute set
// (normals, colour), counted when a client first needs them: a sender
// scratch keeps them, so each worker counts them once.
struct CodeTableCache {
  const SpgView* view = nullptr;
  // Bit k: tables[k] built: attribute set k & 7 (kAttrNormals | kAttrColor |
  // kAttrCurvatureSign of the client's header), protocol 5 at k & 8.
  uint16_t built = 0;
  CodeTables tables[16];
};

// What a sender works in during one update or send, beside its cut's
// scratch: a payload and a frame buffer. Senders used from one thread, one
// at a time, share one (a server: one per worker), so a client's own
// storage is its cut's sent set and a fixed part.
struct SenderScratch {
  static size_t bytes(uint32_t cut_capacity);  // for cuts of up to this many nodes
  void init(void* storage, size_t bytes);      // needs bytes(0) at least
  CutScratch cut;
  uint8_t* payload = nullptr;  // kMaxPayload
  uint8_t* frame = nullptr;    // kMaxFrameBytes
  CodeTableCache* codes = nullptr;
  // The order a change is sent in (StreamSender::update), for changes of up
  // to `order_capacity` nodes each way: 24 bytes a node.
  uint64_t* order = nullptr;    // entering nodes: (projected size << 32 | ~id), then the left node each refines
  uint32_t* left = nullptr;     // the nodes that left, ascending
  uint32_t* waiting = nullptr;  // per left node: its entering descendants not yet sent
  uint32_t* ready = nullptr;    // left nodes whose replacements are all sent, to drop
  uint8_t* sent = nullptr;      // (5) per entering node (ascending ids): sent in this part, for coded batches
  uint32_t order_capacity = 0;
};

class StreamSender {
 public:
  // A cold start's first cut: small enough to cross a 115,200-baud line
  // well within a second, large enough to be a whole silhouette.
  static constexpr uint32_t kCoarseNodes = 128;
  // One block for a client that may see the whole tree: its state and a
  // scratch of its own.
  static size_t storage_bytes(const SpgHeader& header);
  // `view` and `bounds` must outlive the sender.
  [[nodiscard]] bool init(const SpgView& view, const CutBounds& bounds, void* storage, size_t bytes);
  // Over a shared scratch (which must outlive the sender, or be replaced
  // with use_scratch) and state storage for the cut's sent set
  // (view_cut_state_bytes; zero bytes is allowed: see update()).
  [[nodiscard]] bool init(const SpgView& view, const CutBounds& bounds, void* state, size_t state_bytes,
                          const SenderScratch* scratch);
  void use_scratch(const SenderScratch* scratch);
  // Protocol 4 sends each class just before the first node that uses it:
  // the sender keeps which it has sent in `bits` (class_bits_bytes; the
  // one-block init has its own). Without them, a protocol 4 client gets the
  // whole startup, as older ones do. Must outlive the sender (or end()).
  static size_t class_bits_bytes(const SpgHeader& header) {
    return (size_t{header.class_count[0]} + header.class_count[1] + header.class_count[2] + 7) / 8;
  }
  void use_class_bits(uint8_t* bits, size_t bytes) {
    class_bits_ = bits;
    class_bits_bytes_ = bits == nullptr ? 0 : bytes;
  }
  // Moves the cut's state to larger storage (ViewCut::relocate).
  [[nodiscard]] bool relocate(void* state, size_t state_bytes) { return cut_.relocate(state, state_bytes); }
  // The client's hello: sends the reduced startup. False for a hello the
  // server cannot serve (version) — the caller sends a close.
  [[nodiscard]] bool start(const Hello& hello, FrameSink sink, void* context);
  // One camera update: the cut's change as drop and node batches, then an
  // update-end. Returns false when the sink refused a frame, or when the
  // cut outgrew its storage (cut_status() is then kStorageTooSmall and
  // nothing more was sent: grow the scratch or the state, and update again).
  //
  // Coarse to fine (docs/protocol.md "Order"): a client that holds nothing
  // first gets a coarse cut of at most kCoarseNodes nodes (a whole
  // silhouette), then the rest. Entering nodes go largest projected size
  // first; a node that left is dropped as soon as every entering node that
  // refines it has been sent (a picture without holes), one that no longer
  // shows before the nodes, and one that a coarser entering node replaces
  // after them — unless the client's cache could not hold both, when every
  // drop goes first.
  [[nodiscard]] bool update(const CameraUpdate& camera, bool cull, FrameSink sink, void* context);
  // The tag a resuming client names its model by: the CRC-32 of the startup
  // payload a client asking for `attributes` receives (protocol 4: would
  // receive, with every class: its model message carries it; 0 when none).
  uint32_t model_tag(uint8_t attributes) const;
  // A resumed stream (protocol 3): no startup; the client holds `held`
  // (ascending ids) from an earlier stream of this model, so the first
  // update sends only what it lacks. Sends kResumed. False when the hello
  // cannot be served or `held` is not a valid sent set for this state
  // (relocate first: it must hold `count` ids).
  [[nodiscard]] bool resume(const Hello& hello, const NodeId* held, uint32_t count, FrameSink sink, void* context);
  // Ends the stream: the cut is forgotten and its state storage let go (the
  // caller may free it); start() begins a new one.
  void end() {
    cut_.reset();
    (void)cut_.relocate(nullptr, 0);
    started_ = false;
  }
  // Any other message in the stream's sequence (keep-alive, close, error).
  [[nodiscard]] bool send(MessageType type, const uint8_t* payload, size_t size, FrameSink sink, void* context);
  const ViewCut& cut() const { return cut_; }
  CutStatus cut_status() const { return cut_status_; }
  bool started() const { return started_; }
  uint64_t bytes_sent() const { return bytes_sent_; }
  uint16_t next_sequence() const { return sequence_; }
  // Coded batches (protocol 5) send a node's two children that replace it
  // as a split against it (split deltas); off: each child as a node of its
  // own (to measure what splits save). The splits sent so far.
  void use_split_deltas(bool on) { split_deltas_ = on; }
  uint64_t splits_sent() const { return splits_sent_; }

 private:
  uint8_t adopt_hello(const Hello& hello);  // the reduced layout and capacity; the attributes wanted
  // The cut's last change, in the order above, announced (protocol 4) as
  // a part of camera `sequence` with `parts_after` parts to follow.
  bool send_change(uint32_t sequence, uint8_t parts_after, bool ramp, FrameSink sink, void* context);
  bool send_classes(const uint64_t* order, uint32_t count, FrameSink sink, void* context);  // what the nodes lack
  bool take_class(int table, uint32_t index);  // marks it sent; false if it was
  bool send_drops(uint32_t* ids, uint32_t count, FrameSink sink, void* context);  // sorts them (compact batches)
  size_t put_id(uint8_t* out, uint32_t id, uint32_t previous) const;  // a batch's entry id: compact or u32
  bool send_nodes(const uint64_t* order, uint32_t count, FrameSink sink, void* context);  // ids in the low words, inverted
  // (id << 32 | group), ascending; the code tables have gone (send_nodes sends them).
  bool send_coded(const uint64_t* keyed, uint32_t count, FrameSink sink, void* context);
  const CodeTables& code_tables();  // the client's, counted on first use
  bool send_code_tables(FrameSink sink, void* context);
  const SpgView* view_ = nullptr;
  ViewCut cut_;
  SenderScratch own_scratch_;  // with the one-block init
  const SenderScratch* scratch_ = nullptr;
  SpgHeader reduced_{};
  size_t reduced_record_bytes_ = 0;
  bool same_layout_ = true;  // the client takes every attribute: records are copied as they are
  uint32_t capacity_ = 0;
  bool pieces_ = false;         // protocol 4: each class before the first node that uses it
  bool coded_ = false;          // protocol 5: node batches entropy-coded
  uint16_t protocol_ = kProtocolVersion;  // the client's version (its code tables: code_tables())
  bool part_sent_ = false;      // scratch_->sent tracks this part's entering nodes: its batches can be coded
  bool tables_sent_ = false;    // the code message went (just before the first coded batch)
  bool coarse_ = false;         // a cold start's coarse part: compact batches, the code tables not yet
  bool splits_ = false;         // this part's batches may send splits (their parents stay until they come)
  bool split_deltas_ = true;
  uint64_t splits_sent_ = 0;
  uint8_t* class_bits_ = nullptr;  // a bit a class of the reduced tables: sent
  size_t class_bits_bytes_ = 0;
  uint16_t sequence_ = 0;
  uint64_t bytes_sent_ = 0;
  CutStatus cut_status_ = CutStatus::kOk;
  bool started_ = false;
};

enum class ReceiveStatus : uint8_t {
  kOk = 0,
  kBadFrame,       // the frame reader refused a frame (frame_status() says why)
  kBadMessage,     // a message that does not parse, or arrives before the startup
  kCacheRefused,   // the node cache refused the startup or a node (cache_status() says why)
  kClosed,         // the server closed the stream (fault() says why)
};

const char* receive_status_text(ReceiveStatus s);

class StreamReceiver {
 public:
  // `reader_storage` holds the frame reader's buffer (kMaxFrameBytes).
  void init(NodeCache* cache, uint8_t* reader_storage, size_t bytes);
  // Storage for coded batches (protocol 5): a u32 a node of the cache's
  // capacity. Without it, a code message is refused (ask for no coding).
  void use_part_storage(uint32_t* ids, uint32_t capacity) {
    part_ids_ = ids;
    part_capacity_ = ids == nullptr ? 0 : capacity;
    part_count_ = 0;
  }
  static size_t part_storage_bytes(uint32_t cache_capacity) { return 4 * size_t{cache_capacity}; }
  // Takes bytes from the link; applies every whole frame. A fault sticks.
  [[nodiscard]] ReceiveStatus receive(const uint8_t* data, size_t size);
  // The last update-end seen: the camera it answered and the cut's size.
  bool converged(uint32_t camera_sequence) const {
    return has_update_end_ && last_update_.camera_sequence == camera_sequence;
  }
  const UpdateEnd& last_update() const { return last_update_; }
  FrameStatus frame_status() const { return frame_status_; }
  CacheStatus cache_status() const { return cache_status_; }
  const Fault& fault() const { return fault_; }
  // The message that stopped the stream (kBadMessage, kCacheRefused,
  // kClosed): its type and frame sequence.
  uint8_t fault_type() const { return fault_type_; }
  uint16_t fault_sequence() const { return fault_sequence_; }
  uint64_t bytes_received() const { return bytes_; }
  uint32_t frames() const { return frames_; }
  uint64_t nodes_received() const { return nodes_; }  // node entries in node batches
  bool coded() const { return coded_; }  // (5) the stream's node batches come entropy-coded
  // Progress (protocol 4): the part of an update being received (its
  // camera, the nodes entering in it, the parts after it) and how many of its
  // nodes have come.
  const UpdateBegin& part() const { return part_; }
  uint32_t part_nodes() const { return part_nodes_; }
  // The CRC-32 of the last startup payload taken (what a resume names the
  // model by; protocol 4: the model's tag), 0 before any.
  uint32_t startup_crc() const { return startup_crc_; }
  // The sequence the next frame must carry.
  uint16_t expected_sequence() const { return reader_.expected_sequence(); }

 private:
  ReceiveStatus apply(const Frame& frame);

  NodeCache* cache_ = nullptr;
  FrameReader reader_;
  ReceiveStatus status_ = ReceiveStatus::kOk;
  FrameStatus frame_status_ = FrameStatus::kOk;
  CacheStatus cache_status_ = CacheStatus::kOk;
  Fault fault_{};
  uint8_t fault_type_ = 0;
  uint16_t fault_sequence_ = 0;
  UpdateEnd last_update_{};
  bool has_update_end_ = false;
  uint64_t bytes_ = 0, nodes_ = 0;
  uint32_t frames_ = 0;
  uint32_t startup_crc_ = 0;
  UpdateBegin part_{};
  uint32_t part_nodes_ = 0;
  bool compact_ = false;  // the stream began with a model (protocol 4): compact batches; kept across a resume, as the cache
  bool coded_ = false;    // (5) the code tables came: coded batches can be read
  CodeTables code_{};
  // (5) The ids this part of the update brought in coded batches,
  // ascending, at the end of part_ids_[0 .. part_capacity_): a coded
  // entry's reference is the largest of them below it.
  uint32_t* part_ids_ = nullptr;
  uint32_t part_capacity_ = 0, part_count_ = 0;
  ReceiveStatus apply_coded(const Frame& f);
};

}  // namespace stipple
