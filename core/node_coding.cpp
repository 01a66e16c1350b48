// stipple core — entropy-coded node batches. See node_coding.h and
// docs/protocol.md "Coded batches".
#include "core/node_coding.h"

#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "core/view_cut.h"

namespace stipple {
namespace {

constexpr uint32_t kStateLow = 1u << 23;  // the coder's state lies in [kStateLow, 256 kStateLow)
constexpr int kPieceBits = kCodeProbabilityBits;  // raw bits go as uniform symbols of at most this many

int bit_length_minus_one(uint32_t v) { return 31 - __builtin_clz(v); }  // v > 0

// The hybrid integer of v: its token, and the raw bits below it.
struct Hybrid {
  uint32_t token;
  int extra_bits;
  uint32_t extra;
};
Hybrid hybrid(uint32_t v) {
  if (v < 16) return {v, 0, 0};
  const int n = bit_length_minus_one(v);  // >= 4
  return {16u + 2u * static_cast<uint32_t>(n - 4) + ((v >> (n - 1)) & 1u), n - 1, v & ((1u << (n - 1)) - 1u)};
}

// A field's difference from the entry before, wrapped to its width and
// zigzagged (0, -1, 1, -2, ... as 0, 1, 2, 3, ...), and back.
uint32_t zigzag_delta(uint32_t v, uint32_t previous, int bits) {
  const uint32_t mask = (1u << bits) - 1u;
  const uint32_t d = (v - previous) & mask;
  const uint32_t half = 1u << (bits - 1);
  return d < half ? 2u * d : 2u * ((mask + 1u) - d) - 1u;
}
uint32_t undo_zigzag_delta(uint32_t z, uint32_t previous, int bits) {
  const uint32_t mask = (1u << bits) - 1u;
  const uint32_t d = (z & 1u) ? (0u - ((z + 1u) >> 1)) : (z >> 1);
  return (previous + d) & mask;
}

int model_bits(int model, const RecordLayout& layout) {
  if (model == kIdModel || model == kParentModel) return 32;
  if (model == kPointsModel) return 8;
  if (model == kKindModel) return 1;
  return layout.bits[(model - 4) / 4];
}

// The code message's first word: the delta fields in bits 0-17, the frame
// fields (fn θ, φ, ψ) from bit kFrameFieldsShift.
constexpr int kFrameWordShift = kFrameFieldsShift - static_cast<int>(Field::kFnTheta);
constexpr uint32_t fields_word(uint32_t delta_fields, uint32_t frame_fields) {
  return delta_fields | frame_fields << kFrameWordShift;
}

// Calls f(model) for every model a layout uses, in wire order.
template <typename F>
void for_each_model(const RecordLayout& layout, F&& f) {
  f(kIdModel);
  f(kPointsModel);
  f(kKindModel);
  f(kParentModel);
  for (int field = 0; field < kFieldCount; ++field)
    if (layout.bits[field] > 0)
      for (int c = 0; c < (is_position_field(field) ? 4 : 3); ++c) f(field_model(field, c));
}

// log2(x) in 1/256 bits, within 0.09 bits (x > 0): enough to choose a coding.
uint64_t log2_q8(uint64_t x) {
  int n = 0;
  while ((x >> n) > 1) ++n;
  const uint64_t frac = n >= 8 ? (x >> (n - 8)) & 255u : (x << (8 - n)) & 255u;
  return uint64_t(n) * 256u + frac;
}

// Bits (Q8) that coding these token counts costs at their own frequencies.
uint64_t cost_q8(const uint32_t* counts, int n) {
  uint64_t total = 0, cost = 0;
  for (int t = 0; t < n; ++t) total += counts[t];
  if (total == 0) return 0;
  const uint64_t log_total = log2_q8(total);
  for (int t = 0; t < n; ++t)
    if (counts[t] > 0) cost += counts[t] * (log_total - log2_q8(counts[t]));
  return cost;
}

// Frequencies summing to kCodeTotal from counts over the n possible tokens,
// every one of them at least 1 (any value stays codable).
void normalise(const uint32_t* counts, int n, CodeModel* m) {
  uint64_t total = 0;
  for (int t = 0; t < n; ++t) total += uint64_t{counts[t]} + 1u;
  uint32_t f[kMaxTokens];
  uint32_t sum = 0;
  for (int t = 0; t < n; ++t) {
    const uint64_t q = (uint64_t{counts[t]} + 1u) * kCodeTotal / total;
    f[t] = q < 1 ? 1u : static_cast<uint32_t>(q);
    sum += f[t];
  }
  while (sum != kCodeTotal) {
    int largest = 0;
    for (int t = 1; t < n; ++t)
      if (f[t] > f[largest]) largest = t;
    if (sum < kCodeTotal) {
      f[largest] += kCodeTotal - sum;
      sum = kCodeTotal;
    } else {
      const uint32_t take = sum - kCodeTotal < f[largest] - 1u ? sum - kCodeTotal : f[largest] - 1u;
      f[largest] -= take;
      sum -= take;
    }
  }
  m->count = static_cast<uint8_t>(n);
  m->cum[0] = 0;
  for (int t = 0; t < n; ++t) m->cum[t + 1] = static_cast<uint16_t>(m->cum[t] + f[t]);
  index_code_model(m);
}

// A node entry's context: after an adjacent reference (ids one apart; the
// root's "none", 0xFFFFFFFF, counts as id 0's neighbour), else after a far one.
int node_context(const CodedEntry& e) {
  const uint32_t r = e.reference_id;
  return r + 1u == e.id || r == e.id + 1u ? kAdjacentContext : kFarContext;
}

struct Symbol {
  uint16_t start, freq;
};

// The symbols of one value: its token in `m`, then its raw bits in pieces, the top first.
int push_value(const CodeModel& m, uint32_t v, Symbol* out) {
  const Hybrid h = hybrid(v);
  int n = 0;
  out[n++] = Symbol{m.cum[h.token], static_cast<uint16_t>(m.cum[h.token + 1] - m.cum[h.token])};
  for (int left = h.extra_bits; left > 0;) {
    const int p = left < kPieceBits ? left : kPieceBits;
    left -= p;
    const uint32_t piece = (h.extra >> left) & ((1u << p) - 1u);
    const uint32_t freq = kCodeTotal >> p;
    out[n++] = Symbol{static_cast<uint16_t>(piece * freq), static_cast<uint16_t>(freq)};
  }
  return n;
}

}  // namespace

void index_code_model(CodeModel* m) {
  // The largest token whose cum is at or below each bucket's first slot
  // (a token of frequency 0 is never the answer: the one after it starts there too).
  uint32_t t = 0;
  for (uint32_t b = 0; b < (1u << kCodeStartBits); ++b) {
    const uint32_t slot = b << (kCodeProbabilityBits - kCodeStartBits);
    while (t + 1 < m->count && m->cum[t + 1] <= slot) ++t;
    m->start[b] = static_cast<uint8_t>(t);
  }
}

namespace {

// The classes messages' models from every class of the header's tables:
// index gaps (a piece's are small once a view has sent many, and any below
// the count is possible), each value as it is or as its difference from the
// value before it in its class, whichever costs fewer bits.
void build_class_models(const SpgView& view, const SpgHeader& header, bool first_value_delta, CodeTables* out) {
  out->classes = header.version >= 2;
  if (!out->classes) return;
  uint32_t gaps[kMaxTokens] = {};
  const int index_bits = 16;
  for (int t = 0; t < tokens_for_bits(index_bits); ++t) gaps[t] = t < 4 ? 64 : 1;
  normalise(gaps, tokens_for_bits(index_bits), &out->class_model[0]);
  const uint8_t* tables[3] = {view.sigma_p, view.sigma_n, view.sigma_c};
  // A client without the curvature sign reads sigma_n's magnitudes.
  const bool strip_sign = spg_sigma_n_unsigned_for(view.header, header);
  for (int t = 0; t < 3; ++t) {
    const auto value_at = [&](const uint8_t* v) -> uint32_t {
      return t == 1 && strip_sign ? spg_sigma_n_magnitude(load_u16le(v), true) : load_u16le(v);
    };
    out->class_count[t] = header.class_count[t];
    if (header.class_count[t] == 0) continue;
    const uint32_t k = spg_class_values(t);
    for (uint32_t j = 0; j < k; ++j) {
      uint32_t plain[kMaxTokens] = {}, delta[kMaxTokens] = {};
      uint64_t plain_extra = 0, delta_extra = 0;
      // Value 0 against the class before it in a piece: the classes one
      // and three apart stand for a piece's gaps.
      for (uint32_t stride = 1; stride <= 3; stride += 2)
        for (uint32_t c = 0; c < header.class_count[t]; c += stride) {
          const uint8_t* v = tables[t] + 2 * (k * c + j);
          const uint32_t value = value_at(v);
          const Hybrid a = hybrid(value);
          ++plain[a.token];
          plain_extra += static_cast<uint64_t>(a.extra_bits);
          const uint32_t base = j > 0 ? value_at(v - 2) : c >= stride ? value_at(v - 2 * k * stride) : 0;
          const Hybrid d = hybrid(zigzag_delta(value, base, 16));
          ++delta[d.token];
          delta_extra += static_cast<uint64_t>(d.extra_bits);
        }
      const int tokens = tokens_for_bits(16);
      const bool d = (j > 0 || first_value_delta) &&
                     cost_q8(delta, tokens) + 256 * delta_extra < cost_q8(plain, tokens) + 256 * plain_extra;
      if (d) out->class_delta = static_cast<uint16_t>(out->class_delta | (1u << (3 * t + j)));
      normalise(d ? delta : plain, tokens, &out->class_model[1 + 3 * t + j]);
    }
  }
}

// Writes one model: u8 n, n LEB128 frequencies, u8 m (a tail of m ones).
size_t write_model(const CodeModel& m, uint8_t* out) {
  int ones = 0;
  while (ones < m.count && m.cum[m.count - ones] - m.cum[m.count - ones - 1] == 1) ++ones;
  size_t at = 0;
  out[at++] = static_cast<uint8_t>(m.count - ones);
  for (int k = 0; k < m.count - ones; ++k) at += store_leb128(out + at, uint32_t{m.cum[k + 1]} - m.cum[k]);
  out[at++] = static_cast<uint8_t>(ones);
  return at;
}

// Reads one model of at most `alphabet` tokens; false when it does not add up.
bool read_model(const uint8_t** at, const uint8_t* end, int alphabet, CodeModel* m) {
  if (*at == end) return false;
  const uint8_t listed = *(*at)++;
  uint32_t sum = 0;
  for (int k = 0; k < listed; ++k) {
    uint32_t f = 0;
    if (k >= alphabet || !load_leb128(at, end, &f) || f > kCodeTotal - sum) return false;
    sum += f;
    m->cum[k + 1] = static_cast<uint16_t>(sum);
  }
  if (*at == end) return false;
  const uint8_t ones = *(*at)++;
  const int count = listed + ones;
  if (count == 0 || count > alphabet || sum + ones != kCodeTotal) return false;
  for (int k = listed; k < count; ++k) m->cum[k + 1] = static_cast<uint16_t>(++sum);
  m->count = static_cast<uint8_t>(count);
  index_code_model(m);
  return true;
}

}  // namespace

void CodeTally::field(int field, int context, const NodeFields& self, uint32_t base) {
  const int bits = layout.bits[field];
  const uint32_t v = self.v[field];
  const auto tally = [&](int way, uint32_t value) {
    const Hybrid h = hybrid(value);
    ++fields[way][field][context][h.token];
    extra[way][field] += static_cast<uint64_t>(h.extra_bits);
  };
  tally(kPlain, v);
  tally(kDelta, zigzag_delta(v, base, bits));
  if (is_normal_frame_field(field)) tally(kFrame, zigzag_delta(v, frame_base(layout, field, self), bits));
}

void CodeTally::split(const NodeFields& parent, uint32_t parent_points, const NodeFields& first, uint32_t first_points,
                      const NodeFields& second) {
  for (int f = 0; f < kFieldCount; ++f) {
    const int bits = layout.bits[f];
    if (bits == 0) continue;
    field(f, kChildContext, first, parent.v[f]);
    if (is_position_field(f))
      field(f, kSplitContext, second, split_prediction(parent.v[f], first.v[f], parent_points, first_points, bits));
    else
      field(f, kAdjacentContext, second, first.v[f]);
  }
}

void CodeTally::batch(const CodedEntry* entries, uint32_t count) {
  uint32_t previous_id = 0xFFFFFFFFu, previous_parent = 0xFFFFFFFFu;
  for (uint32_t i = 0; i < count;) {
    const CodedEntry* e = entries + i;
    ++kinds[e[0].kind == 0 ? 0 : 1];
    ++ids[hybrid(e[0].id - previous_id - 1u).token];
    ++points[hybrid(e[0].points).token];
    if (e[0].kind == 0) {
      const int context = node_context(e[0]);
      for (int f = 0; f < kFieldCount; ++f)
        if (layout.bits[f] > 0) field(f, context, e[0].fields, e[0].reference.v[f]);
      previous_id = e[0].id;
      i += 1;
      continue;
    }
    if (i + 1 == count) return;  // a split without its second child: encode_coded_nodes refuses it
    ++parents[hybrid(e[0].reference_id - previous_parent - 1u).token];
    if (split_points(e[0].reference_points, e[0].points) > 255) ++points[hybrid(e[1].points).token];
    split(e[0].reference, e[0].reference_points, e[0].fields, e[0].points, e[1].fields);
    previous_id = e[1].id;
    previous_parent = e[0].reference_id;
    i += 2;
  }
}

void CodeTally::tables(const SpgView& view, const SpgHeader& header, uint16_t protocol, CodeTables* out,
                       bool unseen_at_floor) const {
  *out = CodeTables{};
  out->layout = layout;
  // A model of nothing counted, at the floor: token 0 all but one slot of
  // each other token (three bytes on the wire, not one a token).
  const auto fit = [&](const uint32_t* counts, int n, CodeModel* m) {
    bool any = false;
    for (int t = 0; t < n && !any; ++t) any = counts[t] > 0;
    if (any || !unseen_at_floor) return normalise(counts, n, m);
    m->count = static_cast<uint8_t>(n);
    m->cum[0] = 0;
    for (int t = 0; t < n; ++t) m->cum[t + 1] = static_cast<uint16_t>(t == 0 ? kCodeTotal - (n - 1) : m->cum[t] + 1);
    index_code_model(m);
  };
  fit(ids, tokens_for_bits(32), &out->model[kIdModel]);
  fit(parents, tokens_for_bits(32), &out->model[kParentModel]);
  fit(kinds, 2, &out->model[kKindModel]);
  fit(points, tokens_for_bits(8), &out->model[kPointsModel]);
  for (int f = 0; f < kFieldCount; ++f) {
    const int bits = layout.bits[f];
    if (bits == 0) continue;
    const int tokens = tokens_for_bits(bits);
    const int contexts = is_position_field(f) ? 4 : 3;
    // The cheapest way on the counts (the earlier on a tie).
    int best = kPlain;
    uint64_t best_cost = 0;
    for (int way = kPlain; way < (is_normal_frame_field(f) && protocol >= kFrameFieldsProtocol ? kWays : kFrame); ++way) {
      uint64_t cost = 256 * extra[way][f];
      for (int c = 0; c < contexts; ++c) cost += cost_q8(fields[way][f][c], tokens);
      if (way == kPlain || cost < best_cost) best = way, best_cost = cost;
    }
    if (best == kDelta) out->delta_fields |= 1u << f;
    if (best == kFrame) out->frame_fields |= 1u << f;
    for (int c = 0; c < contexts; ++c) fit(fields[best][f][c], tokens, &out->model[field_model(f, c)]);
  }
  build_class_models(view, header, protocol >= kFrameFieldsProtocol, out);
}

void build_code_tables(const SpgView& view, const ViewCut& cut, const SpgHeader& header, uint32_t sample,
                       CodeTables* out, uint16_t protocol) {
  const RecordLayout& layout = header.layout;
  CodeTally tally;  // 62 KB of stack: a server's thread has it
  tally.layout = layout;
  const auto fields_of = [&](uint32_t id) { return unpack_record(view.header.layout, view.records + size_t{id} * view.record_bytes); };
  const uint32_t n = view.header.node_count;
  const uint32_t per_run = 32;
  const uint32_t runs = sample / per_run > 0 ? sample / per_run : 1;
  for (uint32_t r = 0; r < runs; ++r) {
    // A run of entries with id gaps 1, 2, 4, ... 64 as often as 1/2, 1/4, ...
    // (a cut's batch skips what it does not hold), and the splits of the
    // run's nodes that have two children.
    uint32_t id = static_cast<uint32_t>(uint64_t{r} * n / runs);
    if (id >= n) break;
    NodeFields last = fields_of(id);
    for (uint32_t k = 1; k < per_run; ++k) {
      const int tz = __builtin_ctz(k + r);
      const uint32_t gap = 1u << (tz < 6 ? tz : 6);
      if (n - id <= gap) break;
      id += gap;
      const NodeFields f = fields_of(id);
      ++tally.points[hybrid(cut.points(NodeId{id})).token];
      for (int field = 0; field < kFieldCount; ++field)
        if (layout.bits[field] > 0) tally.field(field, gap == 1 ? kAdjacentContext : kFarContext, f, last.v[field]);
      last = f;
      const uint32_t child = cut.first_child(id);
      if (id + 1 < n && cut.first_child(id + 1) == child + 2)
        tally.split(f, cut.points(NodeId{id}), fields_of(child), cut.points(NodeId{child}), fields_of(child + 1));
    }
  }
  // A batch's id gaps depend on how much of the model its part sends, which
  // no sample knows: every gap below the node count alike, by its token;
  // the same for splits' parents, and either kind of entry alike.
  const int id_bits = n > 1 ? bit_length_minus_one(n - 1) + 1 : 1;
  for (int t = 0; t < tokens_for_bits(id_bits); ++t) tally.ids[t] = tally.parents[t] = runs;
  // Splits are a refinement's (an orbit's) entries, few of a cold start's.
  tally.kinds[0] = 15 * runs;
  tally.kinds[1] = runs;
  tally.tables(view, header, protocol, out);
}

uint32_t split_prediction(uint32_t parent, uint32_t first, uint32_t parent_points, uint32_t first_points, int bits) {
  const int32_t p = static_cast<int32_t>(parent), c = static_cast<int32_t>(first);
  int32_t guess = 2 * p - c;
  if (parent_points < 255 && first_points > 0 && parent_points > first_points) {
    const int32_t n = static_cast<int32_t>(parent_points), n1 = static_cast<int32_t>(first_points), n2 = n - n1;
    const int32_t twice = 2 * (n * p - n1 * c) + n2;  // rounded: floor((2 num + n2) / (2 n2))
    guess = twice >= 0 ? twice / (2 * n2) : -((-twice + 2 * n2 - 1) / (2 * n2));
  }
  const int32_t most = static_cast<int32_t>((1u << bits) - 1u);
  return static_cast<uint32_t>(guess < 0 ? 0 : guess > most ? most : guess);
}

size_t write_code_tables(const CodeTables& t, uint8_t* out, size_t capacity) {
  if (capacity < 4) return 0;
  store_u32le(out, fields_word(t.delta_fields, t.frame_fields));
  size_t at = 4;
  bool fits = true;
  const auto put = [&](const CodeModel& m) {  // a model takes at most 2 + 3 x its tokens
    fits = fits && capacity - at >= 5 + 3 * size_t{m.count};
    if (fits) at += write_model(m, out + at);
  };
  for_each_model(t.layout, [&](int model) { put(t.model[model]); });
  if (!fits) return 0;
  out[at++] = t.classes ? 1 : 0;
  if (t.classes) {
    store_u16le(out + at, t.class_delta);
    at += 2;
    put(t.class_model[0]);
    for (int k = 0; k < 3; ++k)
      for (uint32_t j = 0; t.class_count[k] > 0 && j < spg_class_values(k); ++j) put(t.class_model[1 + 3 * k + j]);
  }
  return fits ? at : 0;
}

bool parse_code_tables(const uint8_t* payload, size_t size, const SpgHeader& header, CodeTables* out) {
  if (size < 4) return false;
  *out = CodeTables{};
  const RecordLayout& layout = header.layout;
  out->layout = layout;
  const uint32_t word = load_u32le(payload);
  out->delta_fields = word & ((1u << kFieldCount) - 1u);
  out->frame_fields = (word >> kFrameFieldsShift) << static_cast<int>(Field::kFnTheta);
  if (word != fields_word(out->delta_fields, out->frame_fields) || (out->delta_fields & out->frame_fields) != 0)
    return false;
  for (int field = 0; field < kFieldCount; ++field) {
    const bool coded_as_difference = ((out->delta_fields | out->frame_fields) >> field) & 1u;
    if (coded_as_difference && layout.bits[field] == 0) return false;
    if (((out->frame_fields >> field) & 1u) && (!is_normal_frame_field(field) || layout.bits[field - 4] == 0)) return false;
  }
  const uint8_t* at = payload + 4;
  const uint8_t* end = payload + size;
  bool ok = true;
  for_each_model(layout, [&](int model) {
    ok = ok && read_model(&at, end, tokens_for_bits(model_bits(model, layout)), &out->model[model]);
  });
  if (!ok || at == end) return false;
  const uint8_t classes = *at++;
  if (classes > 1 || (classes == 1) != (header.version >= 2)) return false;
  out->classes = classes == 1;
  if (out->classes) {
    if (end - at < 2) return false;
    out->class_delta = load_u16le(at);
    at += 2;
    if (!read_model(&at, end, tokens_for_bits(16), &out->class_model[0])) return false;
    for (int k = 0; k < 3; ++k) {
      out->class_count[k] = header.class_count[k];
      for (uint32_t j = 0; j < 3; ++j) {
        const bool present = header.class_count[k] > 0 && j < spg_class_values(k);
        if (((out->class_delta >> (3 * k + j)) & 1u) && !present) return false;
        if (present && !read_model(&at, end, tokens_for_bits(16), &out->class_model[1 + 3 * k + j])) return false;
      }
    }
    if (out->class_delta >> 9) return false;
  }
  return at == end;
}

namespace {

// What field `field` of a node goes against, both ends: its own position
// frame's angle (frame fields), `reference` (delta fields) or nothing
// (false). `self` holds at least the node's fields before `field`.
bool difference_base(const CodeTables& t, int field, const NodeFields& self, uint32_t reference, uint32_t* base) {
  if ((t.frame_fields >> field) & 1u) {
    *base = frame_base(t.layout, field, self);
    return true;
  }
  *base = reference;
  return (t.delta_fields >> field) & 1u;
}

// Field `field` of `self` as coded.
uint32_t field_value(const CodeTables& t, int field, const NodeFields& self, uint32_t reference) {
  const int bits = t.layout.bits[field];
  const uint32_t v = self.v[field];
  uint32_t base = 0;
  return difference_base(t, field, self, reference, &base) ? zigzag_delta(v, base, bits) : v & ((1u << bits) - 1u);
}

// Calls f(model, value, node, field) for each value of a unit — a node,
// or a split's two entries — as it is coded, in decoding order: node 0 or
// 1 of the unit, field -1 for its kind, ids and points bytes.
template <typename F>
void for_each_value(const CodeTables& t, const CodedEntry* e, uint32_t previous_id, uint32_t previous_parent, F&& f) {
  if (e[0].kind == 0) {
    f(kKindModel, 0u, 0, -1);
    f(kIdModel, e[0].id - previous_id - 1u, 0, -1);
    f(kPointsModel, uint32_t{e[0].points}, 0, -1);
    const int context = node_context(e[0]);
    for (int k = 0; k < kFieldCount; ++k)
      if (t.layout.bits[k] > 0) f(field_model(k, context), field_value(t, k, e[0].fields, e[0].reference.v[k]), 0, k);
    return;
  }
  const CodedEntry& first = e[0];
  const CodedEntry& second = e[1];
  const NodeFields& parent = first.reference;
  f(kKindModel, 1u, 0, -1);
  f(kParentModel, first.reference_id - previous_parent - 1u, 0, -1);
  f(kIdModel, first.id - previous_id - 1u, 0, -1);
  f(kPointsModel, uint32_t{first.points}, 0, -1);
  for (int k = 0; k < kFieldCount; ++k)
    if (t.layout.bits[k] > 0) f(field_model(k, kChildContext), field_value(t, k, first.fields, parent.v[k]), 0, k);
  if (split_points(first.reference_points, first.points) > 255) f(kPointsModel, uint32_t{second.points}, 1, -1);
  for (int k = 0; k < kFieldCount; ++k) {
    const int bits = t.layout.bits[k];
    if (bits == 0) continue;
    if (is_position_field(k))
      f(field_model(k, kSplitContext),
        field_value(t, k, second.fields,
                    split_prediction(parent.v[k], first.fields.v[k], first.reference_points, first.points, bits)),
        1, k);
    else
      f(field_model(k, kAdjacentContext), field_value(t, k, second.fields, first.fields.v[k]), 1, k);
  }
}

// The symbols of a unit in decoding order.
int unit_symbols(const CodeTables& t, const CodedEntry* e, uint32_t previous_id, uint32_t previous_parent, Symbol* s) {
  int n = 0;
  for_each_value(t, e, previous_id, previous_parent,
                 [&](int model, uint32_t v, int, int) { n += push_value(t.model[model], v, s + n); });
  return n;
}

// Codes symbols s[n - 1] .. s[0] (the decoder reads them s[0] first) onto
// the stream growing down from *p to `floor`; false when it is full.
bool put_symbols(const Symbol* s, int n, uint32_t* x, uint8_t** p, uint8_t* floor) {
  while (n-- > 0) {
    const uint32_t freq = s[n].freq;
    const uint32_t x_max = ((kStateLow >> kCodeProbabilityBits) << 8) * freq;
    while (*x >= x_max) {
      if (*p == floor) return false;
      *--*p = static_cast<uint8_t>(*x);
      *x >>= 8;
    }
    *x = ((*x / freq) << kCodeProbabilityBits) + (*x % freq) + s[n].start;
  }
  return true;
}

// The stream from p to `end` moved down to just after the state, at `state`.
size_t close_stream(uint32_t x, const uint8_t* p, const uint8_t* end, uint8_t* state) {
  const size_t stream = static_cast<size_t>(end - p);
  for (size_t k = 0; k < stream; ++k) state[4 + k] = p[k];  // p >= state + 4: forwards is safe
  store_u32le(state, x);
  return 4 + stream;
}

}  // namespace

void coded_mean_cost_q8(const CodeTables& t, const CodedEntry* e, uint32_t cost[2]) {
  cost[0] = cost[1] = 0;
  for_each_value(t, e, 0xFFFFFFFFu, 0xFFFFFFFFu, [&](int model, uint32_t v, int node, int field) {
    if (field < 0 || !is_position_field(field)) return;
    const CodeModel& m = t.model[model];
    const Hybrid h = hybrid(v);
    const uint32_t freq = uint32_t{m.cum[h.token + 1]} - m.cum[h.token];
    cost[node] += static_cast<uint32_t>(256u * kCodeProbabilityBits - log2_q8(freq) + 256u * static_cast<uint32_t>(h.extra_bits));
  });
}

size_t encode_coded_nodes(const CodeTables& t, const CodedEntry* entries, uint32_t count, uint8_t* out, size_t capacity) {
  if (capacity < 8) return 0;
  uint8_t* const floor = out + 8;
  uint8_t* p = out + capacity;  // the stream grows down from the end, then moves to its start
  uint32_t x = kStateLow;
  for (uint32_t end = count; end > 0;) {
    // The last unit before `end`: a node, or a split's two entries.
    const bool split = entries[end - 1].kind == 2;
    const uint32_t first = split ? end - 2 : end - 1;
    if (split ? end < 2 || entries[first].kind != 1 || entries[end - 1].id != entries[first].id + 1u
              : entries[first].kind != 0)
      return 0;
    // The last split's parent before it (the first from -1).
    uint32_t previous_parent = 0xFFFFFFFFu;
    for (uint32_t k = first; k-- > 0;)
      if (entries[k].kind == 1) {
        previous_parent = entries[k].reference_id;
        break;
      }
    Symbol s[128];
    const int n = unit_symbols(t, entries + first, first > 0 ? entries[first - 1].id : 0xFFFFFFFFu, previous_parent, s);
    if (!put_symbols(s, n, &x, &p, floor)) return 0;
    end = first;
  }
  store_u32le(out, count);
  return 4 + close_stream(x, p, out + capacity, out + 4);
}

size_t encode_coded_classes(const CodeTables& t, int table, const uint16_t* indices, const uint8_t* values,
                            uint32_t count, uint8_t* out, size_t capacity) {
  if (!t.classes || table < 0 || table > 2 || t.class_count[table] == 0 || count == 0 || count > 0xFFFFu ||
      capacity < kCodedClassesHeaderBytes + 4)
    return 0;
  const uint32_t k = spg_class_values(table);
  uint8_t* const floor = out + kCodedClassesHeaderBytes + 4;
  uint8_t* p = out + capacity;
  uint32_t x = kStateLow;
  for (uint32_t i = count; i-- > 0;) {
    Symbol s[16];
    int n = push_value(t.class_model[0], indices[i] - (i > 0 ? indices[i - 1] : 0xFFFFFFFFu) - 1u, s);
    for (uint32_t j = 0; j < k; ++j) {
      const uint8_t* v = values + 2 * (k * i + j);
      // Value 0 against the class before it in the piece, the others against the value before them.
      const uint32_t base = j > 0 ? load_u16le(v - 2) : i > 0 ? load_u16le(v - 2 * k) : 0;
      const bool d = (t.class_delta >> (3 * table + j)) & 1u;
      n += push_value(t.class_model[1 + 3 * table + j], d ? zigzag_delta(load_u16le(v), base, 16) : load_u16le(v), s + n);
    }
    if (!put_symbols(s, n, &x, &p, floor)) return 0;
  }
  out[0] = static_cast<uint8_t>(table);
  out[1] = 0;
  store_u16le(out + 2, static_cast<uint16_t>(count));
  return kCodedClassesHeaderBytes + close_stream(x, p, out + capacity, out + kCodedClassesHeaderBytes);
}

bool CodedClassesReader::init(const CodeTables& tables, const uint8_t* payload, size_t size) {
  if (size < kCodedClassesHeaderBytes || !tables.classes || payload[0] > 2 || payload[1] != 0) return false;
  t_ = &tables;
  table_ = payload[0];
  count_ = load_u16le(payload + 2);
  done_ = 0;
  previous_ = 0xFFFFFFFFu;
  first_value_ = 0;
  return tables.class_count[table_] > 0 && count_ > 0 && count_ <= tables.class_count[table_] &&
         in_.init(payload + kCodedClassesHeaderBytes, size - kCodedClassesHeaderBytes);
}

bool CodedClassesReader::next(uint32_t* index, uint8_t values[6]) {
  if (done_ == count_) return false;
  uint32_t gap = 0;
  if (!in_.value(t_->class_model[0], &gap)) return false;
  const uint64_t i = uint64_t{previous_} + 1u + gap - (done_ == 0 ? uint64_t{1} << 32 : 0);  // the first from -1
  if (i >= t_->class_count[table_]) return false;
  const uint32_t k = spg_class_values(table_);
  uint32_t last = first_value_;  // value 0's base: the class before it in the piece
  for (uint32_t j = 0; j < k; ++j) {
    uint32_t v = 0;
    if (!in_.value(t_->class_model[1 + 3 * table_ + j], &v)) return false;
    if ((t_->class_delta >> (3 * table_ + j)) & 1u) v = undo_zigzag_delta(v, last, 16);
    store_u16le(values + 2 * j, static_cast<uint16_t>(v));
    if (j == 0) first_value_ = v;
    last = v;
  }
  previous_ = static_cast<uint32_t>(i);
  ++done_;
  *index = previous_;
  return true;
}

bool CodedBatchReader::init(const CodeTables& tables, const uint8_t* payload, size_t size, uint32_t node_count) {
  if (size < 8) return false;
  t_ = &tables;
  count_ = load_u32le(payload);
  done_ = 0;
  node_count_ = node_count;
  previous_ = parent_ = 0xFFFFFFFFu;
  pending_ = 0;
  return in_.init(payload + 4, size - 4) && count_ <= node_count;
}

bool RansReader::init(const uint8_t* stream, size_t size) {
  if (size < 4) return false;
  x_ = load_u32le(stream);
  at_ = stream + 4;
  end_ = stream + size;
  return x_ >= kStateLow && x_ < (kStateLow << 8);
}

bool RansReader::token(const CodeModel& m, uint32_t* t) {
  const uint32_t slot = x_ & (kCodeTotal - 1u);
  // The largest token whose cum <= slot: from the slot's bucket, upwards
  // (cum[count] = kCodeTotal > slot stops it).
  uint32_t lo = m.start[slot >> (kCodeProbabilityBits - kCodeStartBits)];
  while (m.cum[lo + 1] <= slot) ++lo;
  x_ = (uint32_t{m.cum[lo + 1]} - m.cum[lo]) * (x_ >> kCodeProbabilityBits) + slot - m.cum[lo];
  while (x_ < kStateLow) {
    if (at_ == end_) return false;
    x_ = (x_ << 8) | *at_++;
  }
  *t = lo;
  return true;
}

bool RansReader::raw(int bits, uint32_t* v) {
  uint32_t value = 0;
  while (bits > 0) {
    const int p = bits < kPieceBits ? bits : kPieceBits;
    bits -= p;
    const uint32_t slot = x_ & (kCodeTotal - 1u);
    const uint32_t piece = slot >> (kPieceBits - p);
    x_ = (kCodeTotal >> p) * (x_ >> kCodeProbabilityBits) + slot - (piece << (kPieceBits - p));
    while (x_ < kStateLow) {
      if (at_ == end_) return false;
      x_ = (x_ << 8) | *at_++;
    }
    value = (value << p) | piece;
  }
  *v = value;
  return true;
}

// The model's token count (checked by parse_code_tables) keeps v below
// 2^(the model's bits).
bool RansReader::value(const CodeModel& m, uint32_t* v) {
  uint32_t t = 0;
  if (m.count == 0 || !token(m, &t)) return false;
  if (t < 16) {
    *v = t;
    return true;
  }
  const int n = static_cast<int>((t - 16) >> 1) + 4;
  uint32_t extra = 0;
  if (!raw(n - 1, &extra)) return false;
  *v = ((2u | ((t - 16) & 1u)) << (n - 1)) | extra;
  return true;
}

bool RansReader::finished() const { return at_ == end_ && x_ == kStateLow; }

bool CodedBatchReader::value(int model, uint32_t* v) { return in_.value(t_->model[model], v); }

bool CodedBatchReader::next(Entry* e) {
  if (done_ == count_ || pending_ != 0) return false;
  uint32_t kind = 0, gap = 0, points = 0;
  if (!value(kKindModel, &kind)) return false;
  if (kind == 1) {
    if (count_ - done_ < 2 || !value(kParentModel, &gap)) return false;
    const uint64_t parent = uint64_t{parent_} + 1u + gap - (parent_ == 0xFFFFFFFFu ? uint64_t{1} << 32 : 0);
    if (parent >= node_count_) return false;
    parent_ = static_cast<uint32_t>(parent);
    e->parent = parent_;
  }
  if (!value(kIdModel, &gap) || !value(kPointsModel, &points)) return false;
  const uint64_t id = done_ == 0 ? uint64_t{gap} : uint64_t{previous_} + 1u + gap;  // the first from -1
  if (id + kind >= node_count_) return false;
  e->kind = static_cast<uint8_t>(kind);
  e->id = previous_ = static_cast<uint32_t>(id);
  e->points = first_points_ = static_cast<uint8_t>(points);
  pending_ = static_cast<uint8_t>(1 + kind);
  return true;
}

bool CodedBatchReader::field(int f, int context, uint32_t reference, const NodeFields& self, uint32_t* v) {
  if (!value(field_model(f, context), v)) return false;
  uint32_t base = 0;
  if (difference_base(*t_, f, self, reference, &base)) *v = undo_zigzag_delta(*v, base, t_->layout.bits[f]);
  return true;
}

bool CodedBatchReader::node(const NodeFields& reference, bool adjacent, NodeFields* fields) {
  if (pending_ != 1) return false;
  NodeFields f{};
  for (int k = 0; k < kFieldCount; ++k) {
    if (t_->layout.bits[k] == 0) continue;
    uint32_t v = 0;
    if (!field(k, adjacent ? kAdjacentContext : kFarContext, reference.v[k], f, &v)) return false;
    f.v[k] = static_cast<uint16_t>(v);
  }
  pending_ = 0;
  ++done_;
  *fields = f;
  return true;
}

bool CodedBatchReader::split(const NodeFields& parent, uint8_t parent_points, NodeFields* first, NodeFields* second,
                             uint8_t* second_points) {
  if (pending_ != 2) return false;
  NodeFields a{}, b{};
  uint32_t v = 0;
  for (int k = 0; k < kFieldCount; ++k) {
    if (t_->layout.bits[k] == 0) continue;
    if (!field(k, kChildContext, parent.v[k], a, &v)) return false;
    a.v[k] = static_cast<uint16_t>(v);
  }
  uint32_t points = split_points(parent_points, first_points_);
  if (points > 255 && !value(kPointsModel, &points)) return false;
  for (int k = 0; k < kFieldCount; ++k) {
    const int bits = t_->layout.bits[k];
    if (bits == 0) continue;
    const bool position = is_position_field(k);
    const uint32_t base = position ? split_prediction(parent.v[k], a.v[k], parent_points, first_points_, bits) : a.v[k];
    if (!field(k, position ? kSplitContext : kAdjacentContext, base, b, &v)) return false;
    b.v[k] = static_cast<uint16_t>(v);
  }
  pending_ = 0;
  done_ += 2;
  previous_ += 1;  // the second child
  *first = a;
  *second = b;
  *second_points = static_cast<uint8_t>(points);
  return true;
}

bool CodedBatchReader::finish() const { return done_ == count_ && pending_ == 0 && in_.finished(); }

}  // namespace stipple
