// stipple core — the node stream's protocol: frames, messages, and an
// incremental frame reader over caller storage (docs/protocol.md is the
// byte-level specification).
//
// A frame is an 8-byte header — type (u8), flags (u8, 0), sequence (u16, +1
// per frame in each direction, wrapping), payload length (u32) — then the
// payload, then the CRC-32 of header and payload (u32). Integers are
// little-endian. A payload is at most kMaxPayload bytes; node batches are
// split across frames to fit. On a serial line every frame is COBS-encoded
// and ends with a zero byte (core/cobs.h), so a receiver resynchronises
// after line noise; on a socket frames follow each other as they are.
//
// Everything here is integer-only, allocation-free and exception-free:
// writers fill a caller buffer and return the bytes written (0 when it is
// too small); the reader validates every field before use and reports the
// first fault with a status a host turns into a message.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/node_format.h"

namespace stipple {

// 2: node entries carry their original point count. 3: a hello may carry a
// token and announce a resume (the nodes a reconnecting client still holds);
// a version 3 server serves version 2 clients as before. 4: the class tables
// in pieces (model, classes) before the nodes that use them, and each
// update's parts announced (update-begin); older clients are served as before.
// 5: a client may ask for entropy-coded node batches (kWantCoded: code,
// coded nodes; core/node_coding.h). 6: the code tables may code the normal
// frame's angles against the node's own position frame and a class piece's
// first values against the previous class's (version 5 clients get tables
// without either). 7: a client may ask for the curvature sign
// (kWantCurvatureSign); a model's signed sigma_n classes go to older
// clients, and to those that do not ask, as their magnitudes.
inline constexpr uint16_t kProtocolVersion = 7;
inline constexpr uint16_t kOldestProtocolVersion = 2;
inline constexpr size_t kFrameHeaderBytes = 8;
inline constexpr size_t kFrameTrailerBytes = 4;
// The largest payload: a startup message with the default client's largest
// class tables (4096 + 4096 + 64 classes: 82,764 bytes as format version 1's
// float32, 41,444 as version 2's codes) fits; node batches
// are split to stay below it.
inline constexpr size_t kMaxPayload = 98304;
inline constexpr size_t kMaxFrameBytes = kFrameHeaderBytes + kMaxPayload + kFrameTrailerBytes;

enum class MessageType : uint8_t {
  // Client -> server.
  kHello = 0x01,      // version, screen, pixel format, attributes wanted, cache capacity
  kCamera = 0x02,     // a camera update (and the cut's threshold and refinement window)
  kKeepAlive = 0x03,  // either direction, empty
  kClose = 0x04,      // either direction: a reason code
  kAck = 0x05,        // serial lines: every server frame before this sequence arrived whole
  kResend = 0x06,     // serial lines: resend from this sequence on (it, or one after it, was lost)
  kResume = 0x07,     // (3) after a hello announcing it: the nodes the client still holds, in parts
  // Server -> client.
  kStartup = 0x81,    // the startup message (.spg header and class tables) for the attributes asked
  kNodes = 0x82,      // nodes entering the client's cut: count, then (id, record) each
  kDrop = 0x83,       // nodes leaving it: count, then ids
  kUpdateEnd = 0x84,  // the update for a camera is complete: the camera's sequence, the cut's size
  kError = 0x85,      // a fault the server saw in the client's stream: code and frame sequence
  kResumed = 0x86,    // (3) the resume was taken: no startup; updates send what the client lacks
  kModel = 0x87,      // (4) the startup's fixed header alone, with the model's tag: classes come in pieces
  kClasses = 0x88,    // (4) a piece of one class table: the classes the next nodes use
  kUpdateBegin = 0x89,  // (4) a part of an update begins: the nodes entering and leaving in it
  kCode = 0x8A,         // (5) the coded batches' tables (core/node_coding.h), before the first
  kCodedNodes = 0x8B,   // (5) a node batch, entropy-coded: count, then the coder's stream
  kCodedClasses = 0x8C, // (5) a piece of one class table, entropy-coded (format version 2 on)
};

bool message_type_known(uint8_t type);
const char* message_type_name(uint8_t type);  // "hello", ... "unknown"

enum class FrameStatus : uint8_t {
  kOk = 0,
  kNeedMore,        // reader: no whole frame yet
  kBadFlags,        // a flags byte other than 0
  kUnknownType,     // a type this version does not define
  kOversized,       // payload length beyond kMaxPayload (or the reader's storage)
  kBadChecksum,     // CRC-32 mismatch
  kOutOfSequence,   // sequence differs from the one expected
  kBadPayload,      // a message whose payload does not parse (length, count, range)
  kTruncated,       // the stream ended inside a frame
};

const char* frame_status_text(FrameStatus s);

// Writes one frame around `payload` into out[0 .. capacity); returns its
// length, or 0 when it does not fit or the payload is too long.
size_t write_frame(MessageType type, uint16_t sequence, const uint8_t* payload, size_t payload_bytes, uint8_t* out,
                   size_t capacity);

// A frame as the reader hands it out: its payload points into the reader's storage.
struct Frame {
  MessageType type = MessageType::kKeepAlive;
  uint16_t sequence = 0;
  const uint8_t* payload = nullptr;
  size_t payload_bytes = 0;
};

// Reads frames from a byte stream fed in pieces of any size, over a caller
// buffer of at least kMaxFrameBytes (or smaller, to refuse larger frames).
// After a fault the reader stays in it (every call returns the fault again)
// until reset(): on a socket the stream cannot be trusted past a bad frame.
class FrameReader {
 public:
  void init(uint8_t* storage, size_t bytes);
  void reset();  // forget buffered bytes and faults; expect sequence 0
  // The sequence the next frame must carry (a serial line's packets are
  // checked one by one: the receiver decides what a gap means).
  void expect(uint16_t sequence) { expected_ = sequence; }
  // Appends bytes; returns how many were taken (fewer when the buffer is full
  // and a frame must be taken out first with next()).
  size_t feed(const uint8_t* data, size_t size);
  // The next whole frame: kOk and *frame, kNeedMore, or a fault. The frame's
  // payload stays valid until the next call of next() or feed().
  [[nodiscard]] FrameStatus next(Frame* frame);
  // The stream ended: kTruncated if bytes of a frame are pending, else kOk.
  FrameStatus finish() const {
    return fault_ != FrameStatus::kOk ? fault_ : used_ > consumed_ ? FrameStatus::kTruncated : FrameStatus::kOk;
  }
  // Where the fault was: the sequence the reader expected.
  uint16_t expected_sequence() const { return expected_; }
  size_t buffered() const { return used_ - consumed_; }

 private:
  uint8_t* buffer_ = nullptr;
  size_t capacity_ = 0, used_ = 0, consumed_ = 0;
  uint16_t expected_ = 0;
  FrameStatus fault_ = FrameStatus::kOk;
};

// ---- Messages: fixed layouts, each with a writer (payload bytes) and a parser.

inline constexpr uint8_t kWantNormals = 1, kWantColor = 2;
// (3) In the attributes: resume frames follow the hello; the startup waits
// for them.
inline constexpr uint8_t kResuming = 0x80;
// (5) In the attributes: node batches entropy-coded (kCode, then kCodedNodes).
inline constexpr uint8_t kWantCoded = 4;
// (7) In the attributes: the sigma_n classes with their curvature sign, when
// the model has one (kAttrCurvatureSign in the startup's flags).
inline constexpr uint8_t kWantCurvatureSign = 8;
inline constexpr size_t kMaxTokenBytes = 64;

struct Hello {
  uint16_t version = kProtocolVersion;
  uint16_t width = 240, height = 320;
  uint8_t pixel_format = 0;     // 0 RGB565, 1 RGB888
  uint8_t attributes = kWantNormals | kWantColor | kWantCurvatureSign;  // what the client will use (and kResuming)
  uint32_t cache_capacity = 30000;                 // nodes the client can hold
  // (3) A pre-shared token, after the fields above (a server started with
  // --token refuses a hello without its token).
  uint8_t token_bytes = 0;
  uint8_t token[kMaxTokenBytes] = {};
};
inline constexpr size_t kHelloBytes = 12;  // without a token
inline constexpr size_t kHelloMaxBytes = kHelloBytes + kMaxTokenBytes;
size_t write_hello(const Hello& h, uint8_t out[kHelloMaxBytes]);  // kHelloBytes + token_bytes
[[nodiscard]] bool parse_hello(const uint8_t* payload, size_t size, Hello* out);
// Whether a hello's token equals `token` (token_bytes long), in time that
// does not depend on where they differ.
bool hello_token_matches(const Hello& h, const uint8_t* token, size_t token_bytes);

// kResume (3): one part of the list of nodes a reconnecting client holds —
// flags (u8: bit 0, the last part), three zero bytes, the model tag (u32:
// the CRC-32 of the startup payload the client holds, which must be the
// one this server would send it), the total count (u32, the same in every
// part), then ids ascending across the parts, each as the LEB128 of its
// difference from the one before (the first from -1): a difference of 0
// names a node twice. Parts stay under kResumePartBytes, so a server's
// small client-frame buffer takes them.
inline constexpr size_t kResumeHeaderBytes = 12;
inline constexpr size_t kResumePartBytes = 4000;
struct ResumePart {
  bool last = false;
  uint32_t model_tag = 0, total = 0;
  const uint8_t* ids = nullptr;  // the LEB128 differences
  size_t ids_bytes = 0;
};
// Writes the next part for ids[*at ..] (ascending; *previous: the id before
// them, 0xFFFFFFFF at first) into out[0 .. capacity); advances *at and
// *previous; returns the payload's length (0: capacity below a header and one id).
size_t write_resume_part(uint32_t model_tag, const uint32_t* ids, uint32_t count, uint32_t* at, uint32_t* previous,
                         uint8_t* out, size_t capacity);
[[nodiscard]] bool parse_resume_part(const uint8_t* payload, size_t size, ResumePart* out);
// The next id of a part's list.
enum class ResumeId : uint8_t { kId, kEnd, kMalformed, kRepeated };
ResumeId next_resume_id(const uint8_t** at, const uint8_t* end, uint32_t* previous, uint32_t* id);

struct CameraUpdate {
  uint32_t sequence = 0;  // the client's camera number, echoed in kUpdateEnd
  Camera camera;
  int32_t max_size_q4 = 32;
  int32_t window[4] = {0, 0, 0, 0};  // refinement window, px; empty: everywhere
  // (4) With a window: keep the refinements of earlier windows (CutParams::accumulate).
  bool accumulate = false;
};
inline constexpr size_t kCameraUpdateBytes = 4 + 17 * 4 + 4 + 16;
// Version 4: a camera may end with u32 flags (bit 0: accumulate; no other).
inline constexpr size_t kCameraUpdateFlagsBytes = kCameraUpdateBytes + 4;
inline constexpr uint32_t kCameraAccumulate = 1;
// Writes the camera message (92 bytes; 96 with accumulate) into `out`,
// which holds kCameraUpdateFlagsBytes; returns its length.
size_t write_camera_update(const CameraUpdate& c, uint8_t* out);
// Checks the camera's ranges as the client's renderer would (focal length,
// near/far, eye); false when a field is out of range.
[[nodiscard]] bool parse_camera_update(const uint8_t* payload, size_t size, CameraUpdate* out);

struct UpdateEnd {
  uint32_t camera_sequence = 0;
  uint32_t sent_nodes = 0;  // the cut's size once this update is applied
};
inline constexpr size_t kUpdateEndBytes = 8;
size_t write_update_end(const UpdateEnd& u, uint8_t out[kUpdateEndBytes]);
[[nodiscard]] bool parse_update_end(const uint8_t* payload, size_t size, UpdateEnd* out);

// kModel: u32 model tag (the CRC-32 of the startup message the client would
// hold with every class: what a resume names the model by), then the fixed
// header of .spg §1 (the full tables' class counts).
inline constexpr size_t kModelTagBytes = 4;

// kClasses: u8 table (0 sigma_p, 1 sigma_n, 2 sigma_c), u8 0, u16 count
// (>= 1), then count entries, class indices ascending: the LEB128 of the
// index's difference from the previous one (the first from -1; 0 names a
// class twice), then the class's values as in .spg §2 for the header's
// version (class_value_bytes each).
inline constexpr size_t kClassesHeaderBytes = 4;
struct ClassesPiece {
  uint8_t table = 0;
  uint16_t count = 0;
  const uint8_t* entries = nullptr;
  size_t entries_bytes = 0;
};
size_t write_classes_header(uint8_t table, uint16_t count, uint8_t out[kClassesHeaderBytes]);
[[nodiscard]] bool parse_classes(const uint8_t* payload, size_t size, ClassesPiece* out);
// The next entry of a piece: its class index and values (`value_bytes`
// long); false at a malformed, repeated or truncated one. `*previous` starts
// at 0xFFFFFFFF.
[[nodiscard]] bool next_class_entry(const uint8_t** at, const uint8_t* end, size_t value_bytes, uint32_t* previous,
                                    uint32_t* index, const uint8_t** values);

// kUpdateBegin: u32 camera sequence, u32 nodes entering in this part, u32
// nodes leaving in it, u8 parts of the update after this one, 3 zero bytes.
struct UpdateBegin {
  uint32_t camera_sequence = 0;
  uint32_t entering = 0, leaving = 0;
  uint8_t parts_after = 0;  // 0: the last part (a cold start sends a coarse part first)
};
inline constexpr size_t kUpdateBeginBytes = 16;
size_t write_update_begin(const UpdateBegin& u, uint8_t out[kUpdateBeginBytes]);
[[nodiscard]] bool parse_update_begin(const uint8_t* payload, size_t size, UpdateBegin* out);

enum class CloseReason : uint8_t {
  kNormal = 0,
  kBadFrame,
  kBadHello,
  kUnsupported,
  kServerFull,
  kShutdown,
  kTimeout,
  kBadToken,   // (3) the server needs a token this hello lacks or gets wrong
  kBadResume,  // (3) a resume the server cannot take (malformed, ids out of range, too many, repeated)
};
const char* close_reason_text(CloseReason r);

// kClose and kError: a reason and, for kError, the frame status and the
// sequence of the frame at fault.
struct Fault {
  CloseReason reason = CloseReason::kNormal;
  FrameStatus status = FrameStatus::kOk;
  uint16_t sequence = 0;
};
inline constexpr size_t kFaultBytes = 4;
size_t write_fault(const Fault& f, uint8_t out[kFaultBytes]);
[[nodiscard]] bool parse_fault(const uint8_t* payload, size_t size, Fault* out);

// kAck and kResend: a server frame sequence (u16) and two zero bytes.
inline constexpr size_t kSequenceBytes = 4;
size_t write_sequence(uint16_t sequence, uint8_t out[kSequenceBytes]);
[[nodiscard]] bool parse_sequence(const uint8_t* payload, size_t size, uint16_t* out);

// kNodes: u32 count, then count x (u32 id, u8 points, record_bytes record). The payload
// must be exactly that long and every id below node_count.
// kDrop: u32 count, then count x u32 id.
// Node batches: how many fit one frame.
// A nodes entry: u32 node id, u8 original points under the node (saturated
// at 255; 0: unknown), then the record.
inline constexpr size_t node_entry_bytes(size_t record_bytes) { return 5 + record_bytes; }
inline constexpr uint32_t nodes_per_frame(size_t record_bytes) {
  return static_cast<uint32_t>((kMaxPayload - 4) / node_entry_bytes(record_bytes));
}
// What a server puts in one node batch: small enough that a client over a
// 115,200-baud line has its first nodes 0.7 s after the startup.
inline constexpr size_t kNodeBatchBytes = 8192;
inline constexpr uint32_t kDropsPerFrame = static_cast<uint32_t>((kMaxPayload - 4) / 4);
// A parsed batch: the entries stay in the payload; read them with node_at / drop_at.
struct NodeBatch {
  uint32_t count = 0;
  size_t record_bytes = 0;
  const uint8_t* entries = nullptr;
  NodeId id(uint32_t i) const;
  uint8_t points(uint32_t i) const { return entries[size_t{i} * node_entry_bytes(record_bytes) + 4]; }
  const uint8_t* record(uint32_t i) const { return entries + size_t{i} * node_entry_bytes(record_bytes) + 5; }
};
[[nodiscard]] bool parse_nodes(const uint8_t* payload, size_t size, size_t record_bytes, uint32_t node_count,
                               NodeBatch* out);
struct DropBatch {
  uint32_t count = 0;
  const uint8_t* ids = nullptr;
  NodeId id(uint32_t i) const;
};
[[nodiscard]] bool parse_drop(const uint8_t* payload, size_t size, uint32_t node_count, DropBatch* out);

// Protocol 4's compact batches (a stream that began with kModel): ids
// ascending, each as the LEB128 of its difference from the one before (the
// first from -1; 0 names a node twice). kNodes: u32 count, then count x (id,
// u8 points, record); kDrop: u32 count, then count ids. parse_compact_*
// checks the whole payload (every id below node_count, the length exact);
// next_compact_* then walks it. A writer stores each id with store_leb128
// (core/spg_writer.h) of its difference from the one before (id + 1 for the
// first).
struct CompactBatch {
  uint32_t count = 0;
  size_t record_bytes = 0;  // 0: a drop batch
  const uint8_t* at = nullptr;
  const uint8_t* end = nullptr;
  uint32_t previous = 0xFFFFFFFFu;
};
[[nodiscard]] bool parse_compact_nodes(const uint8_t* payload, size_t size, size_t record_bytes, uint32_t node_count,
                                       CompactBatch* out);
[[nodiscard]] bool parse_compact_drop(const uint8_t* payload, size_t size, uint32_t node_count, CompactBatch* out);
// The next entry of a parsed batch: its id and (nodes) points and record.
void next_compact(CompactBatch* batch, uint32_t* id, uint8_t* points, const uint8_t** record);

}  // namespace stipple
