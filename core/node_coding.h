// stipple core — entropy-coded node batches (protocol 5, docs/protocol.md
// "Coded batches").
//
// A node batch's entries (id, points byte, record fields) are turned into
// small integers — the id as its difference from the one before, each field
// either as it is or as its difference from the same field of the entry
// before (wrapped to the field's width, zigzagged), whichever the model's
// own records say is cheaper — and each integer into a token and raw extra
// bits (the "hybrid integer" of Brotli and JPEG XL: values below 16 are
// their own token; above, the token holds the bit length and the bit below
// the top one, and the bits under those go raw). The tokens are coded with
// a static-model range coder (rANS, Duda 2013; 32-bit state, bytes out,
// 12-bit probabilities): one model for ids, one for points bytes, and two a
// field — after an entry whose id is one less (most often its sibling) and
// after any other. The models are counted once a model and attribute set
// from a sample of its records and go to the client in one small message
// before the first coded batch (well under a kilobyte).
//
// A client decodes with shifts, one multiply and a binary search of at most
// 72 cumulative frequencies a token: no division, no heap, no floating
// point; the tables are fixed-size members.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/node_format.h"

namespace stipple {

struct SpgView;
class ViewCut;

inline constexpr int kCodeProbabilityBits = 12;
inline constexpr uint32_t kCodeTotal = 1u << kCodeProbabilityBits;
// Tokens of a 32-bit value (the id model's alphabet; fields' and points' are shorter).
inline constexpr int kMaxTokens = 72;
// The models: ids, points bytes, then two a field (indexed by Field; the
// fields a layout lacks have none on the wire).
inline constexpr int kIdModel = 0, kPointsModel = 1;
constexpr int field_model(int field, int context) { return 2 + 2 * field + context; }
inline constexpr int kCodeModels = 2 + 2 * kFieldCount;

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

// Everything both ends need: the layout's present fields, which are coded
// as differences, and the models.
struct CodeTables {
  RecordLayout layout;
  uint32_t delta_fields = 0;  // bit f: field f as its difference from the entry before
  CodeModel model[kCodeModels];
};

// Counts the tables for records of `layout` (the full layout or a reduced
// one: fields it lacks are left out) from a sample of up to `sample` of the
// model's nodes, taken in a deterministic order with id gaps like a cut's.
// The points model from cut.points(). Integer-only; host or server side.
void build_code_tables(const SpgView& view, const ViewCut& cut, const RecordLayout& layout, uint32_t sample,
                       CodeTables* out);

// The code message (kCode): u32 the delta-field bits, then per model in use
// (ids, points, then each field of the layout in order, its two contexts):
// u8 token count n (1..the model's alphabet), then n LEB128 frequencies
// summing to kCodeTotal.
size_t write_code_tables(const CodeTables& t, uint8_t* out, size_t capacity);
// Reads it for records of `layout`; false (and *out unusable) for a
// message that is short, long, or whose models do not add up.
[[nodiscard]] bool parse_code_tables(const uint8_t* payload, size_t size, const RecordLayout& layout, CodeTables* out);

// kCodedNodes: u32 count, then the rANS stream of the count entries (the
// coder's final state, u32, first). An entry: its id (the difference from
// the entry before, less one; the first as it is), its points byte, then its
// fields, each as it is or as its difference from the same field of the
// entry's *reference* — the node with the largest id below it among those
// that came before it in the same part of the update (update-begin), in
// this batch or an earlier one, or the smallest above it from an earlier
// batch, whichever id is nearer (coded_reference; none: zeros). The context
// of an entry's fields is 1 when the two ids differ by one (most often
// siblings).
//
// Encodes ids[0 .. count) (ascending) with their points bytes, fields and
// references (reference_ids[i]: 0xFFFFFFFF for none) into out[0 ..
// capacity); returns the payload's length, 0 when it did not fit.
// An entry's reference: of the nearest ids below and above it that this
// part sent before it (0xFFFFFFFF: none), the nearer; the lower one on a tie.
constexpr uint32_t coded_reference(uint32_t id, uint32_t below, uint32_t above) {
  if (below == 0xFFFFFFFFu) return above;
  if (above == 0xFFFFFFFFu) return below;
  return above - id < id - below ? above : below;
}

size_t encode_coded_nodes(const CodeTables& t, const uint32_t* ids, const uint8_t* points, const NodeFields* fields,
                          const NodeFields* references, const uint32_t* reference_ids, uint32_t count, uint8_t* out,
                          size_t capacity);

// Walks a coded batch entry by entry: next_id() and then, with the
// entry's reference, next_fields(). Every value is checked as it is
// decoded: ids ascending below node_count, fields within their widths; the
// stream must end exactly where the payload does, in the encoder's first
// state (a truncated, padded or corrupt batch fails, at the latest in finish()).
class CodedBatchReader {
 public:
  [[nodiscard]] bool init(const CodeTables& tables, const uint8_t* payload, size_t size, uint32_t node_count);
  uint32_t count() const { return count_; }
  [[nodiscard]] bool next_id(uint32_t* id, uint8_t* points);
  // `reference`: the fields of the entry's reference (zeros for none);
  // `adjacent`: its id is one less than the entry's.
  [[nodiscard]] bool next_fields(const NodeFields& reference, bool adjacent, NodeFields* fields);
  [[nodiscard]] bool finish() const;

 private:
  bool token(int model, uint32_t* t);
  bool raw(int bits, uint32_t* v);
  bool value(int model, uint32_t* v);
  const CodeTables* t_ = nullptr;
  const uint8_t* at_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint32_t x_ = 0, count_ = 0, done_ = 0, node_count_ = 0, previous_ = 0xFFFFFFFFu;
  bool id_pending_ = false;  // next_id() gave an id whose fields are still to come
};

}  // namespace stipple
