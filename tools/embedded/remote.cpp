// stipple — the client end of the node stream. See remote.h.
#include "tools/embedded/remote.h"

#include <poll.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace stipple {
namespace {
constexpr int kKeepAliveMs = 30000;  // a quiet client's keep-alive: well within serve's idle timeout (120 s)
}  // namespace

Hello hello_for(const ClientConfig& config) {
  Hello h;
  h.width = config.raster.width;
  h.height = config.raster.height;
  h.pixel_format = config.raster.format == PixelFormat::kRgb888 ? 1 : 0;
  const bool normals = config.normals && config.shading != ShadingMode::kNone;
  h.attributes = static_cast<uint8_t>((normals ? kWantNormals | kWantCurvatureSign : 0) |
                                      (config.color && !config.grey ? kWantColor : 0) | kWantCoded);
  h.cache_capacity = config.node_capacity;
  return h;
}

void RemoteModel::close() {
  if (transport_ == nullptr) return;
  uint8_t payload[kFaultBytes];
  write_fault(Fault{}, payload);
  std::string ignored;
  options_.reconnect = nullptr;  // a server already gone is not redialled to say goodbye
  (void)send(MessageType::kClose, payload, kFaultBytes, ignored);
  transport_ = nullptr;
}

bool RemoteModel::send(MessageType type, const uint8_t* payload, size_t size, std::string& error) {
  size_t n = write_frame(type, sequence_, payload, size, frame_.data(), frame_.size());
  const uint8_t* bytes = frame_.data();
  if (options_.serial) {
    n = cobs_encode(frame_.data(), n, cobs_out_.data(), cobs_out_.size());
    bytes = cobs_out_.data();
  }
  for (size_t at = 0; at < n;) {
    size_t moved = 0;
    const TransportStatus s = transport_->write(bytes + at, n - at, &moved);
    if ((s == TransportStatus::kClosed || s == TransportStatus::kError) && options_.reconnect != nullptr && !in_reconnect_) {
      // A new link carries the hello and the latest camera (this frame's
      // purpose when it was a camera) again.
      return reconnect(error);
    }
    if (s == TransportStatus::kClosed || s == TransportStatus::kError) return error = went_away(s), false;
    at += moved;
    if (moved == 0) {
      if (options_.pump && !options_.pump(options_.pump_context)) return error = "stopped", false;
      if (options_.fd >= 0) {
        pollfd p{options_.fd, POLLOUT, 0};
        poll(&p, 1, 100);
      }
    }
  }
  ++sequence_;
  bytes_sent_ += n;
  sent_at_ = std::chrono::steady_clock::now();
  return true;
}

bool RemoteModel::done(Awaited what) const {
  return what == Awaited::kStartup ? client_.cache().ready() : receiver_.converged(awaited_camera_);
}

bool RemoteModel::service(int wait_ms, std::string& error) {
  uint8_t buf[16384];
  size_t got = 0;
  const TransportStatus s = transport_->read(buf, sizeof buf, &got);
  const auto now = std::chrono::steady_clock::now();
  if (s == TransportStatus::kOk && got > 0) {
    heard_ = now;
    return take(buf, got, error);
  }
  // A viewer left still says it is there, within the server's idle timeout.
  if (done(awaiting_) && now - sent_at_ > std::chrono::milliseconds(kKeepAliveMs) && s == TransportStatus::kTimeout &&
      !send(MessageType::kKeepAlive, nullptr, 0, error))
    return false;
  // A serial line silent while we wait for something: our hello, camera or
  // resend may have been lost on the way up, or the server's last frames on
  // the way down. Ask again.
  if (options_.serial && !done(awaiting_) && now - heard_ > std::chrono::milliseconds(options_.silence_ms)) {
    heard_ = now;
    if (!ask_again(error)) return false;
  }
  if (s == TransportStatus::kClosed || s == TransportStatus::kError) {
    if (options_.reconnect == nullptr) return error = went_away(s), false;
    return reconnect(error);
  }
  if (options_.pump && !options_.pump(options_.pump_context)) return error = "stopped", false;
  if (options_.fd >= 0 && wait_ms > 0) {
    pollfd p{options_.fd, POLLIN, 0};
    poll(&p, 1, wait_ms);
  }
  return true;
}

bool RemoteModel::wait(Awaited what, std::string& error) {
  const auto start = std::chrono::steady_clock::now();
  heard_ = start;
  const uint64_t received = bytes_received_, damaged = damaged_, resyncs = resyncs_;
  while (!done(what)) {
    if (std::chrono::steady_clock::now() - start > std::chrono::milliseconds(options_.timeout_ms)) {
      // What the wait saw: nothing at all, or bytes that never made a whole answer.
      error = "no answer from the server within " + std::to_string(options_.timeout_ms) + " ms";
      const uint64_t got = bytes_received_ - received;
      if (got == 0) {
        error += ": nothing arrived (is the server running, and on this line at this rate?)";
      } else if (damaged_ > damaged) {
        error += ": " + std::to_string(got) + " bytes arrived, but " + std::to_string(damaged_ - damaged) +
                 " frames were damaged on the way and " + std::to_string(resyncs_ - resyncs) +
                 " resends asked for did not get through whole: the line is too noisy for its rate (a lower --baud, "
                 "a shorter or shielded cable)";
      } else {
        error += ": " + std::to_string(got) + " bytes arrived, but not the answer";
      }
      return false;
    }
    if (!service(100, error)) return false;
  }
  return true;
}

bool RemoteModel::take(const uint8_t* data, size_t size, std::string& error) {
  bytes_received_ += size;
  const auto fail = [&](ReceiveStatus r) {
    if (r == ReceiveStatus::kClosed)
      error = std::string("the server closed the stream: ") + close_reason_text(receiver_.fault().reason);
    else if (r == ReceiveStatus::kBadFrame)
      error = std::string("a frame from the server was refused: ") + frame_status_text(receiver_.frame_status());
    else if (r == ReceiveStatus::kCacheRefused)
      error = std::string("the client refused the server's data: ") + cache_status_text(receiver_.cache_status());
    else
      error = std::string("the server's ") + message_type_name(receiver_.fault_type()) + " message (frame " +
              std::to_string(receiver_.fault_sequence()) + ") was refused: " + receive_status_text(r);
    return false;
  };
  if (!options_.serial) {
    const bool before_startup = !client_.cache().ready();
    if (before_startup && early_.size() < 2 * kMaxFrameBytes) early_.insert(early_.end(), data, data + size);
    ReceiveStatus r = receiver_.receive(data, size);
    if (r == ReceiveStatus::kCacheRefused && receiver_.cache_status() == CacheStatus::kStartupTooLarge && before_startup) {
      // Sized for the startup it received, then the same bytes again.
      const std::vector<uint8_t> bytes = std::move(early_);
      early_.clear();
      if (!fit_startup(bytes.data(), bytes.size(), error)) return false;
      r = receiver_.receive(bytes.data(), bytes.size());
    }
    if (client_.cache().ready()) early_ = {};
    if (r == ReceiveStatus::kClosed && receiver_.fault().reason == CloseReason::kShutdown && options_.reconnect != nullptr &&
        !in_reconnect_) {
      // The server is stopping: another (behind the same address, a
      // balancer) or the same one restarted serves the view again.
      return reconnect(error);
    }
    return r == ReceiveStatus::kOk || fail(r);
  }
  // A serial line: packet by packet, each a whole frame in sequence. Noise
  // costs a resend (go-back-N): a damaged packet, or one whose sequence is
  // not the next, makes the client ask for everything from the next it
  // expects and skip packets until that one comes; what arrived whole before
  // it stays applied.
  for (size_t i = 0; i < size; ++i) {
    const CobsStatus cs = deframer_.push(data[i]);
    if (cs == CobsStatus::kDropped) {
      ++damaged_;
      if (!lost(error)) return false;
    }
    if (cs != CobsStatus::kPacket) continue;
    const uint8_t* p = deframer_.packet();
    const size_t n = deframer_.packet_bytes();
    const bool whole = n >= kFrameHeaderBytes + kFrameTrailerBytes && load_u32le(p + n - 4) == crc32(p, n - 4);
    if (!whole) {
      ++damaged_;
      if (!lost(error)) return false;
      continue;
    }
    const uint16_t sequence = load_u16le(p + 2);
    const bool startup = p[0] == static_cast<uint8_t>(MessageType::kStartup) || p[0] == static_cast<uint8_t>(MessageType::kModel);
    if (startup && sequence == 0 && receiver_.expected_sequence() != 0) {
      // The server started the stream over (it no longer had what we asked
      // for, or it answers a hello): a new cache from this startup, and the
      // view asked for again.
      receiver_.init(&client_.cache(), reader_storage_.data(), reader_storage_.size());
      gap_ = false;
      ReceiveStatus r;
      if (!receive_frame(p, n, r, error)) return false;
      if (r != ReceiveStatus::kOk) return fail(r);
      if (has_camera_) {
        uint8_t payload[kCameraUpdateFlagsBytes];
        if (!send(MessageType::kCamera, payload, write_camera_update(last_camera_, payload), error)) return false;
      }
      continue;
    }
    if (sequence != receiver_.expected_sequence()) {  // one went missing before it
      if (!lost(error)) return false;
      continue;
    }
    gap_ = false;
    ReceiveStatus r;
    if (!receive_frame(p, n, r, error)) return false;
    if (r != ReceiveStatus::kOk) return fail(r);
    // Acknowledge every 8 frames and each update-end: the server forgets
    // what it kept for a resend.
    if (++unacknowledged_ >= 8 || p[0] == static_cast<uint8_t>(MessageType::kUpdateEnd)) {
      unacknowledged_ = 0;
      uint8_t payload[kSequenceBytes];
      write_sequence(receiver_.expected_sequence(), payload);
      if (!send(MessageType::kAck, payload, kSequenceBytes, error)) return false;
    }
  }
  return true;
}

bool RemoteModel::lost(std::string& error) {
  if (gap_) return true;  // asked already; the frames in flight before the resend are skipped
  gap_ = true;
  ++resyncs_;
  uint8_t payload[kSequenceBytes];
  write_sequence(receiver_.expected_sequence(), payload);
  return send(MessageType::kResend, payload, kSequenceBytes, error);
}

bool RemoteModel::ask_again(std::string& error) {
  ++resyncs_;
  uint8_t payload[kCameraUpdateFlagsBytes];
  if (receiver_.expected_sequence() == 0) {  // not even the startup came: the hello may be lost
    uint8_t hello[kHelloMaxBytes];
    return send(MessageType::kHello, hello, write_hello(hello_, hello), error);
  }
  write_sequence(receiver_.expected_sequence(), payload);
  if (!send(MessageType::kResend, payload, kSequenceBytes, error)) return false;
  if (!has_camera_) return true;
  return send(MessageType::kCamera, payload, write_camera_update(last_camera_, payload), error);  // cameras are idempotent
}

bool RemoteModel::reconnect(std::string& error) {
  // While the new link is made, a send on it that fails does not redial.
  in_reconnect_ = true;
  const bool ok = link_again(error);
  in_reconnect_ = false;
  return ok;
}

bool RemoteModel::link_again(std::string& error) {
  int fd = -1;
  Transport* t = options_.reconnect(options_.reconnect_context, &fd);
  if (t == nullptr) return error = "the server went away and did not come back", false;
  transport_ = t;
  options_.fd = fd;
  ++reconnects_;
  // A new stream: the frame reader from sequence 0, the cache from the new
  // startup; the hello, then the view we were waiting for.
  const uint32_t tag = receiver_.startup_crc();
  receiver_.init(&client_.cache(), reader_storage_.data(), reader_storage_.size());
  deframer_.init(cobs_storage_.data(), cobs_storage_.size());
  gap_ = false;
  unacknowledged_ = 0;
  sequence_ = 0;
  // Over a socket, a client holding nodes says which (protocol 3): a server
  // of the same model sends only what it lacks (a server of another model
  // starts over with a startup, which clears the cache).
  const NodeCache& cache = client_.cache();
  const bool resume = !options_.serial && tag != 0 && cache.ready() && cache.count() > 0;
  Hello hello = hello_;
  if (resume) hello.attributes = static_cast<uint8_t>(hello.attributes | kResuming);
  uint8_t hello_bytes[kHelloMaxBytes];
  if (!send(MessageType::kHello, hello_bytes, write_hello(hello, hello_bytes), error)) return false;
  if (resume) {
    std::vector<uint32_t>& held = held_;
    held.clear();
    for (uint32_t slot = 0; slot < cache.count(); ++slot) held.push_back(index_of(cache.id_at(slot)));
    std::sort(held.begin(), held.end());
    uint32_t at = 0, previous = 0xFFFFFFFFu;
    std::vector<uint8_t> part(kResumePartBytes);
    do {
      const size_t n = write_resume_part(tag, held.data(), static_cast<uint32_t>(held.size()), &at, &previous, part.data(),
                                         part.size());
      if (!send(MessageType::kResume, part.data(), n, error)) return false;
    } while (at < held.size());
    ++resumes_;
  }
  uint8_t payload[kCameraUpdateFlagsBytes];
  if (has_camera_) {
    if (!send(MessageType::kCamera, payload, write_camera_update(last_camera_, payload), error)) return false;
  }
  return true;
}

bool RemoteModel::receive_frame(const uint8_t* frame, size_t size, ReceiveStatus& status, std::string& error) {
  status = receiver_.receive(frame, size);
  if (status == ReceiveStatus::kCacheRefused && receiver_.cache_status() == CacheStatus::kStartupTooLarge &&
      (frame[0] == static_cast<uint8_t>(MessageType::kStartup) || frame[0] == static_cast<uint8_t>(MessageType::kModel))) {
    if (!fit_startup(frame, size, error)) return false;  // sized for it, then the same frame again
    status = receiver_.receive(frame, size);
  }
  return true;
}

std::string RemoteModel::went_away(TransportStatus s) const {
  const std::string why = s == TransportStatus::kError ? transport_->last_error() : std::string();
  return "the server went away: " + (why.empty() ? std::string("the link closed (the server stopped, or the cable was pulled)") : why);
}

bool RemoteModel::fit_startup(const uint8_t* frame, size_t size, std::string& error) {
  FrameReader reader;
  std::vector<uint8_t> storage(kMaxFrameBytes);
  reader.init(storage.data(), storage.size());
  Frame f;
  if (reader.feed(frame, size) == 0 || reader.next(&f) != FrameStatus::kOk ||
      (f.type != MessageType::kStartup && f.type != MessageType::kModel))
    return error = "the client refused the server's startup (too large) and it could not be read again", false;
  SpgView view;
  size_t used = 0;
  const bool model = f.type == MessageType::kModel;  // protocol 4: the header alone, after the model's tag
  if (model ? f.payload_bytes < kModelTagBytes ||
                  !spg_parse_header(f.payload + kModelTagBytes, f.payload_bytes - kModelTagBytes, &view.header, &used).ok()
            : !spg_parse_startup(f.payload, f.payload_bytes, &view, &used).ok())
    return error = "the client refused the server's startup: it does not validate", false;
  const SpgHeader& h = view.header;
  ClientConfig wide = config_;
  uint8_t widest = 0;
  for (Field theta : {Field::kFpTheta, Field::kFnTheta, Field::kFcTheta})
    for (int k = 0; k < 3; ++k) widest = std::max<uint8_t>(widest, h.layout.bits[static_cast<int>(theta) + k]);
  wide.max_angle_bits = std::max(wide.max_angle_bits, widest);
  wide.max_record_bytes = std::max<uint8_t>(wide.max_record_bytes, static_cast<uint8_t>(h.layout.record_bytes()));
  for (int c = 0; c < 3; ++c) wide.max_classes[c] = std::max(wide.max_classes[c], h.class_count[c]);
  const size_t bytes = client_arena_bytes(wide);
  char widths[160];
  std::snprintf(widths, sizeof widths, "angle fields of up to %u bits (this client was set up for %u), %u-byte records",
                unsigned{widest}, unsigned{config_.max_angle_bits}, static_cast<unsigned>(h.layout.record_bytes()));
  if (bytes == 0) return error = std::string("the server's model needs ") + widths + ": beyond any client configuration", false;
  arena_.assign(bytes / 8 + 1, 0);
  if (client_.init(wide, arena_.data(), arena_.size() * 8) != ClientStatus::kOk)
    return error = std::string("the client could not be set up for the server's model: ") + widths, false;
  config_ = wide;
  receiver_.init(&client_.cache(), reader_storage_.data(), reader_storage_.size());
  return true;
}

bool RemoteModel::connect(Transport& transport, const ClientConfig& config, const Options& options, std::string& error) {
  transport_ = &transport;
  options_ = options;
  config_ = config;
  early_.clear();
  const size_t bytes = client_arena_bytes(config);
  if (bytes == 0) return error = "invalid client configuration", false;
  arena_.assign(bytes / 8 + 1, 0);
  if (client_.init(config, arena_.data(), arena_.size() * 8) != ClientStatus::kOk)
    return error = "the client could not be set up", false;
  reader_storage_.assign(kMaxFrameBytes, 0);
  frame_.assign(kMaxFrameBytes, 0);
  receiver_.init(&client_.cache(), reader_storage_.data(), reader_storage_.size());
  part_storage_.assign(config.node_capacity, 0);
  receiver_.use_part_storage(part_storage_.data(), config.node_capacity);
  cobs_storage_.assign(kMaxFrameBytes + 16, 0);
  cobs_out_.assign(cobs_bound(kMaxFrameBytes), 0);
  deframer_.init(cobs_storage_.data(), cobs_storage_.size());
  hello_ = hello_for(config);
  if (!options.coded) hello_.attributes = static_cast<uint8_t>(hello_.attributes & ~kWantCoded);
  if (options.token.size() > kMaxTokenBytes)
    return error = "the token is longer than " + std::to_string(kMaxTokenBytes) + " bytes", false;
  hello_.token_bytes = static_cast<uint8_t>(options.token.size());
  for (size_t i = 0; i < options.token.size(); ++i) hello_.token[i] = static_cast<uint8_t>(options.token[i]);
  uint8_t payload[kHelloMaxBytes];
  if (!send(MessageType::kHello, payload, write_hello(hello_, payload), error)) return false;
  return wait(Awaited::kStartup, error);
}

bool RemoteModel::view(const Camera& camera, int32_t max_size_q4, const int32_t window[4], std::string& error) {
  return request(camera, max_size_q4, window, error) && wait(Awaited::kUpdateEnd, error);
}

bool RemoteModel::request(const Camera& camera, int32_t max_size_q4, const int32_t window[4], std::string& error,
                          bool accumulate) {
  CameraUpdate u;
  u.sequence = camera_sequence_;
  u.camera = camera;
  u.max_size_q4 = max_size_q4;
  for (int k = 0; k < 4; ++k) u.window[k] = window[k];
  u.accumulate = accumulate && window[0] < window[2] && hello_.version >= 4;
  last_camera_ = u;
  has_camera_ = true;
  uint8_t payload[kCameraUpdateFlagsBytes];
  if (!send(MessageType::kCamera, payload, write_camera_update(u, payload), error)) return false;
  awaited_camera_ = camera_sequence_++;
  awaiting_ = Awaited::kUpdateEnd;
  heard_ = requested_at_ = std::chrono::steady_clock::now();
  nodes_at_request_ = receiver_.nodes_received();
  return true;
}

bool RemoteModel::converged() const { return done(Awaited::kUpdateEnd); }

RemoteModel::Progress RemoteModel::progress() const {
  Progress p;
  if (converged()) {
    p.known = true;
    p.share = 1;
    return p;
  }
  const UpdateBegin& part = receiver_.part();
  if (!client_.cache().ready() || part.camera_sequence != awaited_camera_ || part.entering == 0) return p;
  p.known = true;
  p.coarse = part.parts_after > 0;
  const uint32_t got = std::min(receiver_.part_nodes(), part.entering);
  p.share = static_cast<double>(got) / part.entering;
  // The rest of this part at the rate nodes have come since the camera
  // (their classes and framing included).
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - requested_at_).count();
  const uint64_t now = receiver_.nodes_received();  // counted afresh after a reconnect
  const uint64_t came = now >= nodes_at_request_ ? now - nodes_at_request_ : now;
  const double rate = seconds > 0 ? static_cast<double>(came) / seconds : 0;
  if (rate > 0) p.seconds_left = static_cast<double>(part.entering - got) / rate;
  return p;
}

bool RemoteModel::render(const Camera& camera, uint8_t* frame, size_t stride, FrameStats* stats, std::string& error) {
  const ClientStatus s = client_.render(camera, frame, stride, stats);
  if (s == ClientStatus::kBadCamera)
    return error = "--camera: the view puts the camera out of the client's range (its distance, field of view or the model's size)", false;
  if (s != ClientStatus::kOk) return error = std::string("client: ") + client_status_text(s), false;
  return true;
}

}  // namespace stipple
