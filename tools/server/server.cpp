// stipple server — see server.h; the protocol is docs/protocol.md.
#include "tools/server/server.h"

#include <poll.h>

#include <cstdio>

#include "core/cobs.h"
#include "platform/tcp/tcp_transport.h"
#include "tools/embedded/embedded.h"

namespace stipple {
namespace {
constexpr size_t kRetainedBytes = size_t{4} << 20;  // most unacknowledged bytes kept for a serial client
}  // namespace

struct Server::Client {
  uint32_t id = 0;
  std::unique_ptr<Transport> transport;
  int fd = -1;
  std::string name;
  std::vector<uint64_t> sender_storage;
  StreamSender sender;
  uint8_t in_storage[4096];  // client -> server frames are small; larger ones are refused
  FrameReader reader;
  std::vector<uint8_t> out;  // frames not yet written (serial: and those not yet acknowledged)
  size_t out_at = 0;
  // Serial: each frame in `out` the client has not acknowledged, oldest
  // first — its sequence and where it starts — for a resend (go-back-N).
  struct Retained {
    uint16_t sequence;
    size_t at;
  };
  std::vector<Retained> retained;
  Hello hello_message;
  uint32_t resends = 0;
  bool hello = false, pending = false, closing = false, gone = false;
  bool serial = false;
  std::vector<uint8_t> cobs_storage;
  CobsDeframer deframer;
  uint32_t dropped_packets = 0;
  CameraUpdate camera;
  ClientReport report;

  static bool sink(void* self, const uint8_t* frame, size_t size) {
    auto* c = static_cast<Client*>(self);
    if (!c->serial) {
      c->out.insert(c->out.end(), frame, frame + size);
      return true;
    }
    const size_t at = c->out.size();
    c->retained.push_back({load_u16le(frame + 2), at});
    c->out.resize(at + cobs_bound(size));
    c->out.resize(at + cobs_encode(frame, size, c->out.data() + at, c->out.size() - at));
    return true;
  }
  bool idle() const { return out_at == out.size(); }

  // Forgets the retained frames before `sequence` that are written, and
  // their bytes once they are many (or all of them).
  void release(uint16_t sequence) {
    size_t n = 0;
    while (n < retained.size() && static_cast<int16_t>(sequence - retained[n].sequence) > 0 &&
           (n + 1 < retained.size() ? retained[n + 1].at : out.size()) <= out_at)
      ++n;
    if (n == 0) return;
    retained.erase(retained.begin(), retained.begin() + static_cast<long>(n));
    const size_t cut = retained.empty() ? out_at : retained.front().at;
    if (cut < (1u << 16) && !retained.empty()) return;  // compact in large steps
    out.erase(out.begin(), out.begin() + static_cast<long>(cut));
    out_at -= cut;
    for (Retained& r : retained) r.at -= cut;
  }
};

Server::Server() = default;
Server::~Server() {
  if (listen_fd_ >= 0) tcp_close(listen_fd_);
}

void Server::log(const std::string& line) const {
  if (options_.log) options_.log(line);
}

bool Server::init(std::vector<uint8_t> file, const std::string& name, const ServerOptions& options, std::string& error) {
  file_ = std::move(file);
  name_ = name;
  options_ = options;
  const SpgResult r = spg_parse(file_.data(), file_.size(), &view_);
  if (!r.ok()) return error = spg_error_message(name, r, file_.size()), false;
  decoder_storage_.assign(node_decoder_bytes(view_.header) / 4 + 1, 0);
  if (decoder_.init(view_, decoder_storage_.data(), decoder_storage_.size() * 4) != DecodeStatus::kOk)
    return error = name + ": the angle fields are wider than the decoder supports", false;
  bounds_storage_.assign(CutBounds::bytes(view_.header) / 8 + 1, 0);
  if (bounds_.init(view_, decoder_, bounds_storage_.data(), bounds_storage_.size() * 8, options_.cones) != CutStatus::kOk)
    return error = name + ": the cut's bounds could not be built", false;
  return true;
}

bool Server::listen_tcp(const std::string& host, uint16_t port, std::string& error) {
  if (!tcp_listen(host, port, &listen_fd_, &port_, error)) return false;
  log("listening on " + (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port_));
  return true;
}

void Server::add_client(std::unique_ptr<Transport> transport, int fd, const std::string& name, bool serial) {
  auto c = std::make_unique<Client>();
  c->serial = serial;
  if (serial) {
    c->cobs_storage.assign(sizeof c->in_storage + 16, 0);
    c->deframer.init(c->cobs_storage.data(), c->cobs_storage.size());
  }
  c->id = next_id_++;
  c->transport = std::move(transport);
  c->fd = fd;
  c->name = "client " + std::to_string(c->id) + " (" + name + ")";
  c->report.name = c->name;
  c->reader.init(c->in_storage, sizeof c->in_storage);
  if (clients_.size() >= options_.max_clients) {
    // No room: a close frame, then gone. The sender is not needed for it.
    log(c->name + ": refused, " + std::to_string(clients_.size()) + " clients already");
    uint8_t payload[kFaultBytes], frame[64];
    write_fault(Fault{CloseReason::kServerFull, FrameStatus::kOk, 0}, payload);
    const size_t n = write_frame(MessageType::kClose, 0, payload, kFaultBytes, frame, sizeof frame);
    size_t moved = 0;
    (void)c->transport->write(frame, n, &moved);
    c->transport->close();
    return;
  }
  c->sender_storage.assign(StreamSender::storage_bytes(view_.header) / 8 + 1, 0);
  if (!c->sender.init(view_, bounds_, c->sender_storage.data(), c->sender_storage.size() * 8)) {
    log(c->name + ": could not be set up");
    return;
  }
  log(c->name + ": connected");
  clients_.push_back(std::move(c));
}

void Server::close_client(Client& c, CloseReason reason, FrameStatus status, uint16_t sequence, const std::string& why) {
  if (c.closing) return;
  uint8_t payload[kFaultBytes];
  write_fault(Fault{reason, status, sequence}, payload);
  (void)c.sender.send(reason == CloseReason::kBadFrame ? MessageType::kError : MessageType::kClose, payload, kFaultBytes,
                      Client::sink, &c);
  c.closing = true;
  log(c.name + ": closing: " + why);
}

void Server::handle(Client& c, const Frame& f) {
  switch (f.type) {
    case MessageType::kHello: {
      // A second hello on a socket: the stream cannot start over mid-byte-stream
      // (and a peer repeating it without reading would grow the queue).
      if (c.hello && !c.serial)
        return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "a second hello on a stream socket");
      if (c.hello && c.serial) {  // a serial client resynchronising: the stream starts over
        c.out.clear();
        c.out_at = 0;
        c.retained.clear();
        c.pending = false;
        log(c.name + ": hello again (resynchronising), " + std::to_string(c.dropped_packets) + " packets dropped so far");
      }
      Hello h;
      if (!parse_hello(f.payload, f.payload_bytes, &h))
        return close_client(c, CloseReason::kBadHello, FrameStatus::kBadPayload, f.sequence, "a malformed hello");
      if (h.version != kProtocolVersion)
        return close_client(c, CloseReason::kUnsupported, FrameStatus::kOk, f.sequence,
                            "protocol version " + std::to_string(h.version));
      if (!c.sender.start(h, Client::sink, &c))
        return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "the hello could not be served");
      c.hello = c.report.hello = true;
      c.hello_message = h;
      char line[160];
      std::snprintf(line, sizeof line, "%s: hello %ux%u %s, attributes%s%s, cache %u nodes", c.name.c_str(), h.width,
                    h.height, h.pixel_format ? "rgb888" : "rgb565", h.attributes & kWantNormals ? " normals" : "",
                    h.attributes & kWantColor ? " colour" : "", h.cache_capacity);
      log(line);
      return;
    }
    case MessageType::kCamera: {
      CameraUpdate u;
      if (!c.hello || !parse_camera_update(f.payload, f.payload_bytes, &u))
        return close_client(c, CloseReason::kBadFrame, FrameStatus::kBadPayload, f.sequence,
                            c.hello ? "a malformed camera update" : "a camera update before the hello");
      c.camera = u;  // only the latest counts
      c.pending = true;
      return;
    }
    case MessageType::kKeepAlive:
      // Answered when nothing else is on its way (which tells the peer the
      // link is alive as well): a peer that repeats it without reading
      // cannot grow the queue.
      if (c.idle()) (void)c.sender.send(MessageType::kKeepAlive, nullptr, 0, Client::sink, &c);
      return;
    case MessageType::kAck:
    case MessageType::kResend: {
      uint16_t sequence = 0;
      if (!parse_sequence(f.payload, f.payload_bytes, &sequence))
        return close_client(c, CloseReason::kBadFrame, FrameStatus::kBadPayload, f.sequence,
                            std::string("a malformed ") + message_type_name(static_cast<uint8_t>(f.type)));
      if (!c.serial || !c.hello) return;  // a socket loses nothing; before the hello there is nothing to resend
      if (f.type == MessageType::kAck) return c.release(sequence);
      for (const Client::Retained& r : c.retained) {
        if (r.sequence == sequence) {  // go back: everything from there is written again
          c.out_at = r.at;
          ++c.resends;
          return;
        }
      }
      if (sequence == c.sender.next_sequence()) return;  // nothing after it was sent yet
      // Not retained any more: the stream starts over, and with it the view.
      log(c.name + ": frame " + std::to_string(sequence) + " asked again is no longer kept: starting over");
      c.out.clear();
      c.out_at = 0;
      c.retained.clear();
      if (!c.sender.start(c.hello_message, Client::sink, &c))
        return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "the stream could not restart");
      c.pending = c.report.updates > 0;
      return;
    }
    case MessageType::kClose:
      log(c.name + ": closed by the client");
      c.gone = true;
      return;
    default:
      return close_client(c, CloseReason::kBadFrame, FrameStatus::kUnknownType, f.sequence,
                          std::string("a ") + message_type_name(static_cast<uint8_t>(f.type)) + " message from a client");
  }
}

size_t Server::step(int timeout_ms) {
  // Wait for any socket: the listener, readable clients, clients with output.
  std::vector<pollfd> fds;
  bool unpolled = false;
  if (listen_fd_ >= 0) fds.push_back({listen_fd_, POLLIN, 0});
  for (const auto& c : clients_) {
    if (c->fd < 0) unpolled = true;
    else fds.push_back({c->fd, static_cast<short>(POLLIN | (c->idle() ? 0 : POLLOUT)), 0});
  }
  if (!fds.empty()) poll(fds.data(), static_cast<nfds_t>(fds.size()), unpolled ? 0 : timeout_ms);
  for (std::string peer; listen_fd_ >= 0;) {
    const int fd = tcp_accept(listen_fd_, &peer);
    if (fd < 0) break;
    add_client(std::make_unique<TcpTransport>(fd, peer), fd, peer);
  }
  for (auto& owned : clients_) {
    Client& c = *owned;
    // In: every whole frame; a fault closes the client with its reason.
    uint8_t buf[4096];
    for (int rounds = 0; rounds < 16 && !c.closing && !c.gone; ++rounds) {
      size_t got = 0;
      const TransportStatus s = c.transport->read(buf, sizeof buf, &got);
      if (s == TransportStatus::kClosed || s == TransportStatus::kError) {
        log(c.name + ": disconnected" + (s == TransportStatus::kError ? std::string(": ") + c.transport->last_error() : "") +
            (c.reader.buffered() > 0 ? " mid-frame" : ""));
        c.gone = true;
        break;
      }
      if (s != TransportStatus::kOk || got == 0) break;
      c.report.bytes_in += got;
      if (c.serial) {
        // Packet by packet: a damaged one is dropped (noise), any sequence is
        // taken (cameras are idempotent, a hello restarts the stream).
        for (size_t i = 0; i < got && !c.closing && !c.gone; ++i) {
          const CobsStatus cs = c.deframer.push(buf[i]);
          if (cs == CobsStatus::kDropped) ++c.dropped_packets;
          if (cs != CobsStatus::kPacket) continue;
          if (c.deframer.packet_bytes() < kFrameHeaderBytes) {
            ++c.dropped_packets;
            continue;
          }
          c.reader.reset();
          c.reader.expect(load_u16le(c.deframer.packet() + 2));
          c.reader.feed(c.deframer.packet(), c.deframer.packet_bytes());
          Frame f;
          if (c.reader.next(&f) == FrameStatus::kOk) handle(c, f);
          else ++c.dropped_packets;
        }
        continue;
      }
      for (size_t at = 0; at < got && !c.closing && !c.gone;) {
        at += c.reader.feed(buf + at, got - at);
        Frame f;
        FrameStatus fs = FrameStatus::kNeedMore;
        while (!c.closing && !c.gone && (fs = c.reader.next(&f)) == FrameStatus::kOk) handle(c, f);
        if (!c.closing && !c.gone && fs != FrameStatus::kNeedMore)
          close_client(c, CloseReason::kBadFrame, fs, c.reader.expected_sequence(),
                       std::string("frame ") + std::to_string(c.reader.expected_sequence()) + ": " + frame_status_text(fs));
      }
    }
    // An update only when everything before it is written: a stalled client
    // keeps just its latest camera.
    if (c.pending && c.idle() && !c.closing && !c.gone) {
      if (!c.serial) {  // a serial client's queue keeps what is not acknowledged
        c.out.clear();
        c.out_at = 0;
      }
      const size_t before = c.out.size();
      c.pending = false;
      if (c.sender.update(c.camera, options_.cull, Client::sink, &c)) {
        if (c.report.updates++ == 0)
          log(c.name + ": first cut " + std::to_string(c.sender.cut().sent_count()) + " nodes, " +
              std::to_string(c.out.size() - before) + " bytes");
        c.report.cut_nodes = c.sender.cut().sent_count();
      }
    }
    // Out: as much as the link takes now.
    while (!c.idle() && !c.gone) {
      size_t moved = 0;
      const TransportStatus s = c.transport->write(c.out.data() + c.out_at, c.out.size() - c.out_at, &moved);
      c.out_at += moved;
      c.report.bytes_out += moved;
      if (s == TransportStatus::kClosed || s == TransportStatus::kError) {
        log(c.name + ": disconnected while sending");
        c.gone = true;
      }
      if (s != TransportStatus::kOk || moved == 0) break;
    }
    if (c.idle() && c.out.size() > (1u << 20)) {  // keep the queue's memory bounded
      if (!c.serial) {
        c.out.clear();
        c.out.shrink_to_fit();
        c.out_at = 0;
      } else if (c.out.size() > kRetainedBytes) {
        // A client that does not acknowledge: the oldest frames go (asked
        // for again, the stream starts over).
        c.release(c.sender.next_sequence());
      }
    }
    if (c.closing && c.idle()) c.gone = true;
    c.report.queued_bytes = c.out.size();
  }
  for (size_t i = 0; i < clients_.size();) {
    if (clients_[i]->gone) {
      Client& c = *clients_[i];
      log(c.name + ": removed after " + std::to_string(c.report.updates) + (c.report.updates == 1 ? " update" : " updates") + " (last cut " +
          std::to_string(c.report.cut_nodes) + " nodes), " + std::to_string(c.report.bytes_out) + " bytes sent" +
          (c.serial ? ", " + std::to_string(c.resends) + " resends, " + std::to_string(c.dropped_packets) + " packets dropped"
                    : std::string()));
      c.transport->close();
      clients_.erase(clients_.begin() + static_cast<long>(i));
    } else {
      ++i;
    }
  }
  return clients_.size();
}

std::vector<ClientReport> Server::report() const {
  std::vector<ClientReport> out;
  for (const auto& c : clients_) out.push_back(c->report);
  return out;
}

}  // namespace stipple
