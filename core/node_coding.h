// stipple core — entropy-coded node batches (protocol 5, docs/protocol.md
// "Coded batches").
//
// A node batch's entries (id, points byte, record fields) are turned into
// small integers — the id as its difference from the one before, each field
// either as it is or as its difference from the same field of the entry's
// reference (a node the client already holds: the nearest one this part of
// the update sent, or a split's parent), wrapped to the field's width and
// zigzagged, whichever the model's own records say is cheaper — and each
// integer into a token and raw extra bits (the "hybrid integer" of Brotli
// and JPEG XL: values below 16 are their own token; above, the token holds
// the bit length and the bit below the top one, and the bits under those go
// raw). The tokens are coded with a static-model range coder (rANS, Duda
// 2013; 32-bit state, bytes out, 12-bit probabilities), a model per kind of
// value and context (below). Class pieces go the same way (format version
// 2 on). The models are counted once a model and attribute set from a
// sample of its records and its classes, and go to the client in one
// message (1.7 KB for the dragon) before the first coded batch.
//
// A client decodes with shifts, one multiply and a short scan from a
// 64-entry start table a token, and one integer division a split: no heap,
// no floating point; the tables are fixed-size members.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/node_format.h"
#include "core/spg_format.h"

namespace stipple {

class ViewCut;

inline constexpr int kCodeProbabilityBits = 12;
inline constexpr uint32_t kCodeTotal = 1u << kCodeProbabilityBits;
// Tokens of a 32-bit value (the id model's alphabet; fields' and points' are shorter).
inline constexpr int kMaxTokens = 72;
// The models: ids, points bytes, entry kinds, parents' ids, then four a
// field, by context: after a reference (0), after an adjacent one (1: its id
// differs by one, most often a sibling), a split's first child against its
// parent (2), a split's second child's mean against its prediction from the
// parent and the first child (3; position fields only). The fields a layout
// lacks have none on the wire.
inline constexpr int kIdModel = 0, kPointsModel = 1, kKindModel = 2, kParentModel = 3;
inline constexpr int kFarContext = 0, kAdjacentContext = 1, kChildContext = 2, kSplitContext = 3;
constexpr int field_model(int field, int context) { return 4 + 4 * field + context; }
inline constexpr int kCodeModels = 4 + 4 * kFieldCount;
constexpr bool is_position_field(int field) { return field <= static_cast<int>(Field::kPosZ); }

// Tokens a model needs for values below 2^bits.
constexpr int tokens_for_bits(int bits) { return bits <= 4 ? 1 << bits : 16 + 2 * (bits - 4); }
static_assert(tokens_for_bits(32) == kMaxTokens);

// One static model: cumulative frequencies, cum[0] = 0, cum[count] =
// kCodeTotal, and where a decoder starts looking for a slot's token.
inline constexpr int kCodeStartBits = 6;
struct CodeModel {
  uint8_t count = 0;  // tokens in use (0 .. count-1); those above have frequency 0
  uint16_t cum[kMaxTokens + 1] = {};
  uint8_t start[1 << kCodeStartBits] = {};  // per slot >> (12 - 6): the token of the slot's first value
};
// Fills m.start from m.cum (a model made by hand must call it).
void index_code_model(CodeModel* m);

// The normal frame's angles (fn θ, φ, ψ) may go as their difference from
// the same angle of the node's own position frame, scaled to their width
// (frame_base): with normals, fp's f3 is oriented along the node's mean
// normal and fn's z is that normal, so their θ and φ nearly agree. In the
// code message's first word, bit kFrameFieldsShift + k stands for field
// kFnTheta + k (the bits below are the delta fields).
inline constexpr int kFrameFieldsShift = 24;
// The protocol version that reads frame fields and a class piece's first
// values as differences (docs/protocol.md, "Versions").
inline constexpr uint16_t kFrameFieldsProtocol = 6;
constexpr bool is_normal_frame_field(int field) {
  return field >= static_cast<int>(Field::kFnTheta) && field <= static_cast<int>(Field::kFnPsi);
}
// Field `field`'s prediction from the node's own position frame (`self`
// holds at least that frame's angles).
constexpr uint32_t frame_base(const RecordLayout& layout, int field, const NodeFields& self) {
  const int own = field >= 4 ? field - 4 : 0;  // fn θ, φ, ψ <- fp θ, φ, ψ (the guard: any field stays in bounds)
  const int from = layout.bits[own], to = layout.bits[field];
  const uint32_t v = self.v[own];
  return from >= to ? v >> (from - to) : v << (to - from);
}

// Everything both ends need: the layout's present fields, how each is
// coded, and the models.
struct CodeTables {
  RecordLayout layout;
  uint32_t delta_fields = 0;  // bit f: field f as its difference from the entry's reference
  uint32_t frame_fields = 0;  // bit f: field f (a normal frame's angle) as its difference from frame_base
  CodeModel model[kCodeModels];
  // Coded classes (format version 2 and later: 16-bit class values): the
  // tables' class counts, the models of index gaps (0) and of value j of
  // table t (1 + 3 t + j), and bit 3 t + j of class_delta: that value as
  // its difference from value j - 1 of the same class, value 0 from value
  // 0 of the class before it in the piece (0 for the first; the encoder
  // numbers classes by size).
  bool classes = false;
  uint16_t class_count[3] = {};
  uint16_t class_delta = 0;
  CodeModel class_model[10];
};
inline constexpr size_t kCodedClassesHeaderBytes = 4;

// Counts the tables for records of `header`'s layout (the full header or a
// reduced one: fields and class tables it lacks are left out) from a
// sample of up to `sample` of the model's nodes, taken in a deterministic
// order with id gaps like a cut's, and (format version 2 on) from every
// class of its tables. The points model from cut.points(). Integer-only;
// host or server side.
// `protocol`: the client's version — below 6, no frame fields and no class
// value 0 as a difference (what a version 5 client reads).
void build_code_tables(const SpgView& view, const ViewCut& cut, const SpgHeader& header, uint32_t sample,
                       CodeTables* out, uint16_t protocol = kFrameFieldsProtocol);

// One entry to encode. `kind` 0: a node, with its reference; 1: a split's
// first child, with its parent as the reference (`reference_points` the
// parent's points byte) — the next entry must be its sibling (kind 2, id + 1,
// its reference unused).
struct CodedEntry {
  uint32_t id = 0;
  uint8_t points = 0, kind = 0, reference_points = 0;
  uint32_t reference_id = 0xFFFFFFFFu;
  NodeFields fields, reference;
};

// Token counts of what a coder codes, and the tables fitted to them: a
// server's from a sample of the model (build_code_tables), a whole file's
// (format version 3, core/spg_coded.h) from every entry it codes. 62 KB.
struct CodeTally {
  enum Way { kPlain, kDelta, kFrame, kWays };  // a field as it is, against its base, against its own frame
  RecordLayout layout;
  uint32_t ids[kMaxTokens] = {}, parents[kMaxTokens] = {}, kinds[2] = {}, points[kMaxTokens] = {};
  uint32_t fields[kWays][kFieldCount][4][kMaxTokens] = {};
  uint64_t extra[kWays][kFieldCount] = {};  // raw bits each way costs
  // Field `field` of `self` in `context`, every way it may go; `base` what a difference goes against.
  void field(int field, int context, const NodeFields& self, uint32_t base);
  // A split's children's fields against their parent, as they are coded.
  void split(const NodeFields& parent, uint32_t parent_points, const NodeFields& first, uint32_t first_points,
             const NodeFields& second);
  // One batch's entries as encode_coded_nodes codes them (each id after
  // the one before it, each split's parent after the split's before it).
  void batch(const CodedEntry* entries, uint32_t count);
  // Models of these counts, each field the cheapest way it may go (below
  // protocol 6, never against its own frame), and the class models (a
  // header of version 2 on). Every value stays codable in every model
  // unless `unseen_at_floor`: a model nothing was counted in is then all
  // but one slot a token its first (tables counted on every entry they
  // will code, a file's, need no more).
  void tables(const SpgView& view, const SpgHeader& header, uint16_t protocol, CodeTables* out,
              bool unseen_at_floor = false) const;
};

// The decoding end of the coder over one stream: its final state (u32),
// then its bytes.
class RansReader {
 public:
  [[nodiscard]] bool init(const uint8_t* stream, size_t size);
  // A hybrid integer in model m (a model without tokens decodes nothing).
  [[nodiscard]] bool value(const CodeModel& m, uint32_t* v);
  // Every byte taken, and the encoder's first state reached.
  bool finished() const;

 private:
  bool token(const CodeModel& m, uint32_t* t);
  bool raw(int bits, uint32_t* v);
  const uint8_t* at_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint32_t x_ = 0;
};

// The code message (kCode): u32 the delta-field bits (bits 0-17) and the
// frame-field bits (kFrameFieldsShift + 0..2), then per model in use
// (ids, points, kinds, parents, then each field of the layout in order, its
// contexts: three, four for the mean's): u8 n, n LEB128 frequencies, u8 m:
// m more tokens of frequency 1 — n + m tokens, 1 .. the model's alphabet,
// frequencies summing to kCodeTotal. Then u8 1 and the class models (u16
// class_delta, the index gaps' model, each present table's values' models,
// as above), or u8 0: none (a format version 1 header).
size_t write_code_tables(const CodeTables& t, uint8_t* out, size_t capacity);
// Reads it for records of `layout`; false (and *out unusable) for a
// message that is short, long, or whose models do not add up.
[[nodiscard]] bool parse_code_tables(const uint8_t* payload, size_t size, const SpgHeader& header, CodeTables* out);

// kCodedClasses (with class models): u8 table, u8 0, u16 count (>= 1), then
// the rANS stream (final state first) of count classes, indices ascending:
// each the index's difference from the one before, less one (the first as
// it is), then its values, each as it is or as its difference (class_delta:
// from the value before it in the class, value 0 from the previous class's
// value 0), 16-bit. `values`: the classes' values as
// in .spg §2, spg_class_values(table) little-endian u16 each. Returns the
// payload's length, 0 when it did not fit.
size_t encode_coded_classes(const CodeTables& t, int table, const uint16_t* indices, const uint8_t* values,
                            uint32_t count, uint8_t* out, size_t capacity);
class CodedClassesReader {
 public:
  // False for a table the tables have no models for, a count of 0 or beyond
  // the table's classes, or a short payload.
  [[nodiscard]] bool init(const CodeTables& tables, const uint8_t* payload, size_t size);
  int table() const { return table_; }
  uint32_t count() const { return count_; }
  // The next class: its index (ascending, below the table's count) and its
  // values as .spg §2 stores them (little-endian u16 each).
  [[nodiscard]] bool next(uint32_t* index, uint8_t values[6]);
  [[nodiscard]] bool finish() const { return done_ == count_ && in_.finished(); }

 private:
  const CodeTables* t_ = nullptr;
  RansReader in_;
  int table_ = 0;
  uint32_t count_ = 0, done_ = 0, previous_ = 0xFFFFFFFFu, first_value_ = 0;
};

// kCodedNodes: u32 count (nodes), then the rANS stream of its entries (the
// coder's final state, u32, first). An entry is one node, or a *split*: the
// two children of a node the client holds (they replace it), coded against
// it. Each begins with its kind (0 a node, 1 a split) and then:
//
// - a node: its id (the difference from the last id before it, less one;
//   the first as it is), its points byte, and its fields, each as it is or
//   as its difference from the same field of its *reference* — the node
//   with the nearest id to it, below or above (the lower on a tie), among
//   those this part of the update (update-begin) sent before it
//   (coded_reference; none: zeros), in context 1 when the two ids differ by
//   one, else 0;
// - a split: its parent's id (the difference from the last split's parent
//   in the batch, less one; the first as it is), the first child's id (as a
//   node's) and points byte, its fields against the parent's (context 2),
//   the second child's points byte unless the parent's (below 255) gives it,
//   then the second child's fields: the mean against its prediction from
//   the parent and the first child (split_prediction; context 3), the rest
//   against the first child's (context 1). The second child's id is the
//   first's plus one.
//
// Fields the code message marks as differences (from the reference, or a
// normal frame's angle from its own position frame's: frame_base) are
// wrapped to their width and zigzagged; the others go as they are, in the
// same contexts.

// An entry's reference: of the nearest ids below and above it that this
// part sent before it (0xFFFFFFFF: none), the nearer; the lower one on a tie.
constexpr uint32_t coded_reference(uint32_t id, uint32_t below, uint32_t above) {
  if (below == 0xFFFFFFFFu) return above;
  if (above == 0xFFFFFFFFu) return below;
  return above - id < id - below ? above : below;
}

// The second child's points byte from its parent's and its sibling's, when
// the parent's is not saturated; 256 when it must be sent.
constexpr uint32_t split_points(uint32_t parent, uint32_t first) {
  return parent < 255 && parent >= first ? parent - first : 256u;
}

// A split's second child's mean, one axis, from its parent's and its first
// sibling's (TOG05's count-weighted mix: the parent holds both children's
// points) within the field's `bits`: (n p - n1 c1) / (n - n1) rounded, with
// the points bytes as counts; 2 p - c1 (equal counts) where they are
// saturated or unknown. One division a split, no floating point.
uint32_t split_prediction(uint32_t parent, uint32_t first, uint32_t parent_points, uint32_t first_points, int bits);

// Encodes entries[0 .. count) (ids ascending) into out[0 .. capacity);
// returns the payload's length, 0 when it did not fit or a split is malformed.
size_t encode_coded_nodes(const CodeTables& t, const CodedEntry* entries, uint32_t count, uint8_t* out, size_t capacity);

// What the mean (the position fields) of each node of a unit costs as
// encode_coded_nodes codes it, in 1/256 bits (within 0.09 bits a value):
// cost[0] the unit's first node's, cost[1] a split's second's. Host side: a
// file's report (tools/encoder/coded_file.h).
void coded_mean_cost_q8(const CodeTables& t, const CodedEntry* unit, uint32_t cost[2]);

// Walks a coded batch: next() gives an entry's kind and ids; then, with its
// reference's fields (a node's reference, or a split's parent, which the
// caller looks up), node() or split() decodes the rest. Every value is
// checked as it is decoded: ids ascending below node_count, fields within
// their widths; the stream must end exactly where the payload does, in the
// encoder's first state (a truncated, padded or corrupt batch fails, at the
// latest in finish()).
class CodedBatchReader {
 public:
  struct Entry {
    uint8_t kind = 0;       // 0 a node, 1 a split
    uint32_t id = 0;        // the node, or the split's first child (the second is id + 1)
    uint8_t points = 0;     // the node's or the first child's
    uint32_t parent = 0;    // a split's
  };
  [[nodiscard]] bool init(const CodeTables& tables, const uint8_t* payload, size_t size, uint32_t node_count);
  uint32_t count() const { return count_; }
  uint32_t done() const { return done_; }  // nodes decoded
  [[nodiscard]] bool next(Entry* e);
  // A node's fields; `reference`: zeros for none, `adjacent`: its id differs by one.
  [[nodiscard]] bool node(const NodeFields& reference, bool adjacent, NodeFields* fields);
  // A split's children's fields and the second's points byte, against the parent's.
  [[nodiscard]] bool split(const NodeFields& parent, uint8_t parent_points, NodeFields* first, NodeFields* second,
                           uint8_t* second_points);
  [[nodiscard]] bool finish() const;

 private:
  bool value(int model, uint32_t* v);
  // Field `field` of a node whose earlier fields `self` holds, against `reference`.
  bool field(int field, int context, uint32_t reference, const NodeFields& self, uint32_t* v);
  const CodeTables* t_ = nullptr;
  RansReader in_;
  uint32_t count_ = 0, done_ = 0, node_count_ = 0, previous_ = 0xFFFFFFFFu, parent_ = 0xFFFFFFFFu;
  uint8_t pending_ = 0;  // 1 a node, 2 a split whose fields are still to come
  uint8_t first_points_ = 0;
};

}  // namespace stipple
