// The node stream end to end, without a socket (core/stream.h): a server's
// StreamSender for the bunny feeds a client's StreamReceiver frame by frame;
// after each camera update the client's frame equals, byte for byte, the
// frame of a client loaded fresh with the same cut from the local file. A
// client asking for fewer attributes gets smaller records and the picture
// those attributes give; the orbit streams a small share of the cut; a
// corrupted or reordered stream is refused and the cache stays as it was.
#include <gtest/gtest.h>

#include <vector>

#include "core/spg_writer.h"
#include "core/stream.h"
#include "raster/point_renderer.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

struct Model : test::ParsedModel {
  std::vector<uint64_t> bounds_storage;
  CutBounds bounds;
  Model() : ParsedModel("tests/golden/bunny_v1.spg") {
    bounds_storage.resize(CutBounds::bytes(view.header) / 8 + 1);
    EXPECT_EQ(bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8), CutStatus::kOk);
  }
};
const Model& bunny() {
  static const Model m;
  return m;
}

// A client: a node cache and a renderer over its own storage.
struct Device {
  std::vector<uint64_t> cache_storage, renderer_storage;
  NodeCache cache;
  PointRenderer renderer;
  std::vector<uint8_t> frame = std::vector<uint8_t>(240 * 320 * 2);
  explicit Device(uint32_t capacity = 8000, ShadingMode shading = ShadingMode::kPerPoint) {
    NodeCacheLimits l;
    l.node_capacity = capacity;
    cache_storage.resize(node_cache_bytes(l) / 8 + 1);
    EXPECT_EQ(cache.init(l, cache_storage.data(), cache_storage.size() * 8), CacheStatus::kOk);
    RendererConfig r;
    r.raster = RasterConfig{240, 320, 5, PixelFormat::kRgb565, 200000};
    r.shading = shading;
    renderer_storage.resize(point_renderer_bytes(r) / 8 + 1);
    EXPECT_EQ(renderer.init(r, renderer_storage.data(), renderer_storage.size() * 8), RenderStatus::kOk);
  }
  const std::vector<uint8_t>& draw(const Camera& c) {
    EXPECT_EQ(renderer.render(cache, c, frame.data(), 240 * 2), RenderStatus::kOk);
    return frame;
  }
};

struct Link {
  std::vector<uint8_t> bytes;
  static bool sink(void* self, const uint8_t* frame, size_t size) {
    auto* l = static_cast<Link*>(self);
    l->bytes.insert(l->bytes.end(), frame, frame + size);
    return true;
  }
};

Camera camera(double yaw, double pitch, double distance) {
  Camera c;
  EXPECT_TRUE(orbit_camera(test::orbit(bunny().decoder.extent_mu(), yaw, pitch, distance), 240, 320, &c));
  return c;
}

// A server's sender for a model and a client's receiver over its cache,
// each over storage of its own, and the link between them.
struct Session {
  std::vector<uint64_t> sender_storage;
  StreamSender sender;
  Device client;
  std::vector<uint8_t> reader_storage = std::vector<uint8_t>(kMaxFrameBytes);
  StreamReceiver receiver;
  std::vector<uint32_t> part_storage = std::vector<uint32_t>(8000);
  Link link;
  Session(const SpgView& view, const CutBounds& bounds, ShadingMode shading = ShadingMode::kPerPoint)
      : sender_storage(StreamSender::storage_bytes(view.header) / 8 + 1), client(8000, shading) {
    EXPECT_TRUE(sender.init(view, bounds, sender_storage.data(), sender_storage.size() * 8));
    receiver.init(&client.cache, reader_storage.data(), reader_storage.size());
    receiver.use_part_storage(part_storage.data(), 8000);
  }
};

// 24 cameras streamed to a client asking for coded batches or not; after
// each, its frame equals a fresh local load's. The bytes: the cold start's
// and the 23 updates'.
struct OrbitBytes {
  uint64_t cold = 0, orbit = 0;
  uint32_t code_word = 0;  // the code message's first word (how each field goes)
};
void stream_an_orbit(bool coded, OrbitBytes& bytes, uint16_t version = kProtocolVersion) {
  const Model& m = bunny();
  Session session(m.view, m.bounds);
  StreamSender& sender = session.sender;
  Device& client = session.client;
  StreamReceiver& receiver = session.receiver;
  Link& link = session.link;
  Hello hello;
  hello.version = version;
  hello.cache_capacity = 8000;
  if (coded) hello.attributes |= kWantCoded;
  ASSERT_TRUE(sender.start(hello, Link::sink, &link));
  ASSERT_EQ(receiver.receive(link.bytes.data(), link.bytes.size()), ReceiveStatus::kOk);
  uint64_t& cold = bytes.cold;
  uint64_t& orbit = bytes.orbit;
  cold = link.bytes.size();
  uint64_t resend = 0;
  std::vector<uint8_t> points(m.view.header.node_count);
  spg_node_points(m.view, points.data(), 1);
  for (uint32_t step = 0; step < 24; ++step) {
    CameraUpdate u;
    u.sequence = step;
    u.camera = camera(30 + 15.0 * step, 20 + (step % 5) * 3.0, 2.0 + (step % 3) * 0.5);
    link.bytes.clear();
    ASSERT_TRUE(sender.update(u, true, Link::sink, &link));
    // The bytes arrive in pieces, as over a wire.
    for (size_t at = 0; at < link.bytes.size(); at += 1000)
      ASSERT_EQ(receiver.receive(link.bytes.data() + at, std::min<size_t>(1000, link.bytes.size() - at)), ReceiveStatus::kOk)
          << receive_status_text(receiver.receive(nullptr, 0));
    ASSERT_TRUE(receiver.converged(step));
    ASSERT_EQ(client.cache.count(), sender.cut().sent_count());
    (step == 0 ? cold : orbit) += link.bytes.size();
    for (size_t at = 0; step == 0 && at < link.bytes.size();) {
      if (link.bytes[at] == static_cast<uint8_t>(MessageType::kCode))
        bytes.code_word = load_u32le(link.bytes.data() + at + kFrameHeaderBytes);
      at += kFrameHeaderBytes + load_u32le(link.bytes.data() + at + 4) + kFrameTrailerBytes;
    }
    resend += sender.cut().sent_count() * node_entry_bytes(m.view.record_bytes);
    // Every node arrived with the original points under it.
    for (uint32_t slot = 0; slot < client.cache.count(); ++slot)
      ASSERT_EQ(client.cache.points_at(slot), points[index_of(client.cache.id_at(slot))]) << "slot " << slot;
    // A fresh client loaded locally with the same cut draws the same bytes.
    Device local;
    ASSERT_EQ(local.cache.load_startup(m.file.data(), spg_startup_bytes(m.view.header.version, m.view.header.class_count)), CacheStatus::kOk);
    for (uint32_t i = 0; i < sender.cut().sent_count(); ++i) {
      const uint32_t id = index_of(sender.cut().sent()[i]);
      ASSERT_EQ(local.cache.put(NodeId{id}, m.view.records + size_t{id} * m.view.record_bytes, m.view.record_bytes, points[id]),
                CacheStatus::kOk);
    }
    ASSERT_EQ(client.draw(u.camera), local.draw(u.camera)) << "step " << step;
  }
  EXPECT_EQ(receiver.coded(), coded);  // the code tables came with the first update
  std::printf("%s: cold start %llu bytes; 23 updates %llu bytes (%.1f %% of resending the cut each time)\n",
              coded ? "coded" : "compact", static_cast<unsigned long long>(cold), static_cast<unsigned long long>(orbit),
              100.0 * static_cast<double>(orbit) / static_cast<double>(resend));
  EXPECT_LT(orbit, resend / 10);
}

TEST(Stream, ClientFramesEqualAFreshLocalLoadAfterEveryUpdate) {
  OrbitBytes b;
  stream_an_orbit(false, b);
}

// Protocol 5's coded batches (core/node_coding.h) bring the same nodes, so
// the same frames, in fewer bytes.
TEST(Stream, CodedBatchesDrawTheSameFramesInFewerBytes) {
  OrbitBytes compact, coded;
  stream_an_orbit(false, compact);
  stream_an_orbit(true, coded);
  EXPECT_LT(coded.cold, compact.cold * 95 / 100);
  EXPECT_LT(coded.orbit, compact.orbit * 95 / 100);
  // Version 6 tables code the normal frame's θ and φ against the node's own position frame.
  EXPECT_EQ(coded.code_word >> kFrameFieldsShift, 3u);
}

// A version 5 client (stop 49's) reads tables without the frame fields:
// the server counts its tables apart, and it draws the same frames.
TEST(Stream, AVersionFiveClientGetsTablesItReads) {
  OrbitBytes five, six;
  stream_an_orbit(true, five, 5);
  stream_an_orbit(true, six);
  ASSERT_NE(five.code_word, 0u);
  EXPECT_EQ(five.code_word >> kFrameFieldsShift, 0u);
  EXPECT_LT(six.cold, five.cold);
}

// A model with the curvature's sign (the bunny's default encoding) streams
// it to the clients that ask (protocol 7, kWantCurvatureSign): their sigma_n
// classes are the file's, concave ones negative. Every other client — one
// that does not ask, a version 6 one — gets no sign flag and the classes'
// magnitudes, coded or not, so it shades as before the sign.
TEST(Stream, TheCurvatureSignGoesToTheClientsThatAskForIt) {
  const test::ParsedModel m("tests/golden/bunny_v2.spg");
  ASSERT_TRUE(m.view.header.has_curvature_sign());
  std::vector<uint64_t> bounds_storage(CutBounds::bytes(m.view.header) / 8 + 1);
  CutBounds bounds;
  ASSERT_EQ(bounds.init(m.view, m.decoder, bounds_storage.data(), bounds_storage.size() * 8), CutStatus::kOk);
  const struct {
    uint16_t version;
    bool ask, coded;
  } clients[] = {{kProtocolVersion, true, true}, {kProtocolVersion, true, false}, {kProtocolVersion, false, true},
                 {6, false, true}, {6, false, false}};
  for (const auto& c : clients) {
    Session session(m.view, bounds, ShadingMode::kSurface);
    StreamSender& sender = session.sender;
    Device& client = session.client;
    StreamReceiver& receiver = session.receiver;
    Link& link = session.link;
    Hello hello;
    hello.version = c.version;
    hello.cache_capacity = 8000;
    hello.attributes = static_cast<uint8_t>(kWantNormals | (c.coded ? kWantCoded : 0) | (c.ask ? kWantCurvatureSign : 0));
    ASSERT_TRUE(sender.start(hello, Link::sink, &link));
    CameraUpdate u;
    u.camera = camera(30, 20, 2.0);
    ASSERT_TRUE(sender.update(u, true, Link::sink, &link));
    ASSERT_EQ(receiver.receive(link.bytes.data(), link.bytes.size()), ReceiveStatus::kOk);
    EXPECT_EQ(client.cache.header().has_curvature_sign(), c.ask) << c.version << " " << c.ask << " " << c.coded;
    uint32_t sent = 0, concave = 0;
    for (uint32_t k = 0; k < m.view.header.class_count[1]; ++k) {
      const int32_t* got = client.cache.decoder().sigma_n_q12(ClassId{static_cast<uint16_t>(k)});
      if (got[0] == 0 && got[1] == 0) continue;  // not sent
      ++sent;
      for (int j = 0; j < 2; ++j) {
        const int32_t file = spg_sigma_n_q12(load_u16le(m.view.sigma_n + 4 * k + 2 * j), true);
        ASSERT_EQ(got[j], c.ask ? file : file < 0 ? -file : file) << "class " << k;
        concave += got[j] < 0;
      }
    }
    EXPECT_GT(sent, 40u);
    EXPECT_EQ(concave > 0, c.ask);
    client.draw(u.camera);
  }
}

// A coded stream's receiver needs the tables before a coded batch, and its
// part storage, and refuses a stream that lacks either.
TEST(Stream, CodedBatchesNeedTheirTablesAndTheirStorage) {
  const Model& m = bunny();
  std::vector<uint64_t> sender_storage(StreamSender::storage_bytes(m.view.header) / 8 + 1);
  StreamSender sender;
  ASSERT_TRUE(sender.init(m.view, m.bounds, sender_storage.data(), sender_storage.size() * 8));
  Link link;
  Hello hello;
  hello.attributes |= kWantCoded;
  ASSERT_TRUE(sender.start(hello, Link::sink, &link));
  const std::vector<uint8_t> start = link.bytes;
  CameraUpdate u;
  u.camera = camera(30, 20, 3);
  link.bytes.clear();
  ASSERT_TRUE(sender.update(u, true, Link::sink, &link));
  const std::vector<uint8_t> update = link.bytes;
  // The code tables go just before the first coded batch: after a cold
  // start's coarse part, which goes compact.
  size_t code_at = 0, code_bytes = 0;
  bool compact_nodes_before = false;
  for (size_t at = 0; at < update.size();) {
    const size_t n = kFrameHeaderBytes + load_u32le(update.data() + at + 4) + kFrameTrailerBytes;
    if (update[at] == static_cast<uint8_t>(MessageType::kNodes)) compact_nodes_before = true;
    if (update[at] == static_cast<uint8_t>(MessageType::kCode)) {
      code_at = at;
      code_bytes = n;
      break;
    }
    ASSERT_NE(update[at], static_cast<uint8_t>(MessageType::kCodedNodes)) << "a coded batch before the tables";
    at += n;
  }
  ASSERT_GT(code_bytes, 0u);
  EXPECT_TRUE(compact_nodes_before);
  const uint8_t after = update[code_at + code_bytes];  // the first coded batch's classes, or the batch
  EXPECT_TRUE(after == static_cast<uint8_t>(MessageType::kClasses) || after == static_cast<uint8_t>(MessageType::kCodedNodes))
      << int{after};
  std::vector<uint8_t> reader_storage(kMaxFrameBytes);
  std::vector<uint32_t> part(8000);
  {  // Without part storage, the code message is refused.
    Device client;
    StreamReceiver r;
    r.init(&client.cache, reader_storage.data(), reader_storage.size());
    ASSERT_EQ(r.receive(start.data(), start.size()), ReceiveStatus::kOk);
    EXPECT_EQ(r.receive(update.data(), update.size()), ReceiveStatus::kBadMessage);
    EXPECT_FALSE(r.coded());
    EXPECT_EQ(r.fault_type(), static_cast<uint8_t>(MessageType::kCode));  // names the message it refused
    EXPECT_EQ(r.fault_sequence(), load_u16le(update.data() + code_at + 2));
  }
  {  // Without the code message (its frame cut out, the sequence mended), the first coded batch is refused.
    Device client;
    StreamReceiver r;
    r.init(&client.cache, reader_storage.data(), reader_storage.size());
    r.use_part_storage(part.data(), 8000);
    ASSERT_EQ(r.receive(start.data(), start.size()), ReceiveStatus::kOk);
    std::vector<uint8_t> rest(update.begin(), update.begin() + static_cast<ptrdiff_t>(code_at));
    rest.insert(rest.end(), update.begin() + static_cast<ptrdiff_t>(code_at + code_bytes), update.end());
    // Renumber the frames after the cut one lower and mend their CRCs.
    for (size_t at = code_at; at < rest.size();) {
      const size_t n = kFrameHeaderBytes + load_u32le(rest.data() + at + 4);
      store_u16le(rest.data() + at + 2, static_cast<uint16_t>(load_u16le(rest.data() + at + 2) - 1));
      store_u32le(rest.data() + at + n, crc32(rest.data() + at, n));
      at += n + kFrameTrailerBytes;
    }
    EXPECT_EQ(r.receive(rest.data(), rest.size()), ReceiveStatus::kBadMessage);
    EXPECT_GT(client.cache.count(), 0u);  // the coarse part came
    EXPECT_EQ(r.fault_type(), static_cast<uint8_t>(MessageType::kCodedNodes));  // the batch without its tables
  }
  {  // Part storage smaller than the part: refused, not overrun.
    Device client;
    StreamReceiver r;
    r.init(&client.cache, reader_storage.data(), reader_storage.size());
    r.use_part_storage(part.data(), 8);
    ASSERT_EQ(r.receive(start.data(), start.size()), ReceiveStatus::kOk);
    EXPECT_EQ(r.receive(update.data(), update.size()), ReceiveStatus::kBadMessage);
  }
  {  // Whole, it converges.
    Device client;
    StreamReceiver r;
    r.init(&client.cache, reader_storage.data(), reader_storage.size());
    r.use_part_storage(part.data(), 8000);
    ASSERT_EQ(r.receive(start.data(), start.size()), ReceiveStatus::kOk);
    ASSERT_EQ(r.receive(update.data(), update.size()), ReceiveStatus::kOk);
    EXPECT_TRUE(r.converged(0));
    EXPECT_EQ(client.cache.count(), sender.cut().sent_count());
  }
}

TEST(Stream, FewerAttributesMeanSmallerRecordsAndTheirPicture) {
  const Model& m = bunny();
  std::vector<uint64_t> sender_storage(StreamSender::storage_bytes(m.view.header) / 8 + 1);
  StreamSender sender;
  ASSERT_TRUE(sender.init(m.view, m.bounds, sender_storage.data(), sender_storage.size() * 8));
  Device grey, flat(8000, ShadingMode::kNone);
  std::vector<uint8_t> reader_storage(kMaxFrameBytes);
  StreamReceiver receiver;
  receiver.init(&grey.cache, reader_storage.data(), reader_storage.size());
  Link link;
  Hello hello;
  hello.attributes = 0;  // no lighting, no colour
  ASSERT_TRUE(sender.start(hello, Link::sink, &link));
  CameraUpdate u;
  u.camera = camera(30, 20, 3);
  ASSERT_TRUE(sender.update(u, false, Link::sink, &link));
  ASSERT_EQ(receiver.receive(link.bytes.data(), link.bytes.size()), ReceiveStatus::kOk);
  EXPECT_FALSE(grey.cache.header().has_normals());
  EXPECT_EQ(grey.cache.record_bytes(), 9u);  // 13 with normals
  // The same picture as the full records drawn without shading.
  ASSERT_EQ(flat.cache.load_startup(m.file.data(), spg_startup_bytes(m.view.header.version, m.view.header.class_count)), CacheStatus::kOk);
  for (uint32_t i = 0; i < sender.cut().sent_count(); ++i) {
    const uint32_t id = index_of(sender.cut().sent()[i]);
    ASSERT_EQ(flat.cache.put(NodeId{id}, m.view.records + size_t{id} * m.view.record_bytes, m.view.record_bytes),
              CacheStatus::kOk);
  }
  EXPECT_EQ(grey.draw(u.camera), flat.draw(u.camera));
}

TEST(Stream, CorruptOrReorderedStreamsAreRefusedAndTheCacheStaysConsistent) {
  const Model& m = bunny();
  std::vector<uint64_t> sender_storage(StreamSender::storage_bytes(m.view.header) / 8 + 1);
  StreamSender sender;
  ASSERT_TRUE(sender.init(m.view, m.bounds, sender_storage.data(), sender_storage.size() * 8));
  Link link;
  ASSERT_TRUE(sender.start(Hello{}, Link::sink, &link));
  CameraUpdate u;
  u.camera = camera(30, 20, 3);
  ASSERT_TRUE(sender.update(u, true, Link::sink, &link));
  const std::vector<uint8_t> good = link.bytes;
  const size_t startup_frame = kFrameHeaderBytes + load_u32le(good.data() + 4) + kFrameTrailerBytes;
  std::vector<uint8_t> reader_storage(kMaxFrameBytes);
  {  // A flipped bit in the first node batch: refused; the cache holds the startup and nothing else.
    std::vector<uint8_t> bad = good;
    bad[startup_frame + 40] ^= 0x01;
    Device d;
    StreamReceiver r;
    r.init(&d.cache, reader_storage.data(), reader_storage.size());
    EXPECT_EQ(r.receive(bad.data(), bad.size()), ReceiveStatus::kBadFrame);
    EXPECT_EQ(r.frame_status(), FrameStatus::kBadChecksum);
    EXPECT_TRUE(d.cache.ready());
    EXPECT_EQ(d.cache.count(), 0u);
    EXPECT_EQ(r.receive(good.data(), good.size()), ReceiveStatus::kBadFrame);  // the fault sticks
  }
  {  // Node records before any startup: refused as out of order.
    std::vector<uint8_t> late(good.begin() + static_cast<long>(startup_frame), good.end());
    late[2] = 0;  // renumber as the first frame
    late[3] = 0;
    const size_t body = kFrameHeaderBytes + load_u32le(late.data() + 4);
    store_u32le(late.data() + body, crc32(late.data(), body));
    Device d;
    StreamReceiver r;
    r.init(&d.cache, reader_storage.data(), reader_storage.size());
    EXPECT_EQ(r.receive(late.data(), late.size()), ReceiveStatus::kBadMessage);
    EXPECT_FALSE(d.cache.ready());
  }
  {  // A client cache too small for the server's cut: refused by the cache, with its reason.
    Device d(10);
    StreamReceiver r;
    r.init(&d.cache, reader_storage.data(), reader_storage.size());
    EXPECT_EQ(r.receive(good.data(), good.size()), ReceiveStatus::kCacheRefused);
    EXPECT_EQ(r.cache_status(), CacheStatus::kFull);
    EXPECT_EQ(d.cache.count(), 10u);
  }
}

}  // namespace
}  // namespace stipple
