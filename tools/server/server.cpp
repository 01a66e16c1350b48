// stipple server — see server.h; the protocol is docs/protocol.md.
#include "tools/server/server.h"

#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/cobs.h"
#include "platform/tcp/tcp_transport.h"
#include "tools/embedded/embedded.h"

namespace stipple {
namespace {
constexpr size_t kRetainedBytes = size_t{4} << 20;  // most unacknowledged bytes kept for a serial client
constexpr size_t kQueueKept = size_t{16} << 10;      // an idle socket client's queue keeps at most this much memory
constexpr int kReopenMs = 500;                       // a hung-up line is tried again this often
constexpr int kAcceptPauseMs = 100;                  // accept failing (out of descriptors): the listener rests

// "address" of "address:port" or "[address]:port".
std::string address_of(const std::string& peer) {
  const size_t colon = peer.rfind(':');
  std::string a = colon == std::string::npos ? peer : peer.substr(0, colon);
  if (a.size() >= 2 && a.front() == '[' && a.back() == ']') a = a.substr(1, a.size() - 2);
  return a;
}
}  // namespace

struct Server::Client {
  uint32_t id = 0;
  std::unique_ptr<Transport> transport;
  int fd = -1;
  std::string name;
  std::string address;  // the peer's address, for the per-address limit (empty: not a socket)
  std::vector<uint8_t> state;  // the cut's sent set (LEB128 differences): grows with the client's cut, never with the model
  std::vector<uint8_t> class_bits;  // protocol 4: the classes sent, a bit each (from the hello)
  StreamSender sender;
  Reopen reopen;                // a serial line: how to open it again after a hang-up
  bool detached = false;        // a serial line that hung up, waiting for its device
  std::chrono::steady_clock::time_point opened, heard, retry;
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
  uint32_t session_from = 0;  // report.updates when the session began
  // A resume being received (protocol 3): the hello that announced it, the
  // parts' model tag and count, and the ids so far.
  bool resuming = false;
  uint32_t resume_tag = 0, resume_total = 0, resume_previous = 0xFFFFFFFFu;
  std::vector<uint32_t> held;
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
  // Out: as much of the queue as the link takes now. False when the link is gone.
  bool write_out() {
    while (!idle()) {
      size_t moved = 0;
      const TransportStatus s = transport->write(out.data() + out_at, out.size() - out_at, &moved);
      out_at += moved;
      report.bytes_out += moved;
      if (s == TransportStatus::kClosed || s == TransportStatus::kError) return false;
      if (s != TransportStatus::kOk || moved == 0) break;
    }
    return true;
  }
  uint64_t state_bytes() const {
    return sizeof(Client) + state.capacity() + held.capacity() * 4 + out.capacity() + retained.capacity() * sizeof(Retained) +
           cobs_storage.capacity() + name.capacity() + address.capacity();
  }

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

bool Server::init(std::shared_ptr<const ServedModel> model, const ServerOptions& options, std::string& error) {
  if (model == nullptr) return error = "no model", false;
  model_ = std::move(model);
  options_ = options;
  // The work space of one update: grown to the largest cut served (update()).
  scratch_storage_.assign(SenderScratch::bytes(4096) / 8 + 1, 0);
  scratch_.init(scratch_storage_.data(), scratch_storage_.size() * 8);
  return true;
}

bool Server::init(std::vector<uint8_t> file, const std::string& name, const ServerOptions& options, std::string& error) {
  auto model = std::make_shared<ServedModel>();
  if (!model->adopt(std::move(file), name, options.cones, error)) return false;
  return init(std::move(model), options, error);
}

bool Server::listen_tcp(const std::string& host, uint16_t port, std::string& error, bool share_port) {
  if (!tcp_listen(host, port, &listen_fd_, &port_, error, share_port)) return false;
  const std::string where = (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port_);
  const bool loopback = host.rfind("127.", 0) == 0 || host == "::1";
  log("listening on " + where +
      (loopback ? std::string() : " — reachable beyond this machine: serve only what may be seen, or put it behind a firewall"));
  return true;
}

void Server::add_client(std::unique_ptr<Transport> transport, int fd, const std::string& name, bool serial,
                        Reopen reopen) {
  auto c = std::make_unique<Client>();
  c->serial = serial;
  c->reopen = std::move(reopen);
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
  c->opened = c->heard = Clock::now();
  const auto refuse = [&](const std::string& why) {
    // A close frame, then gone. The sender is not needed for it.
    log(c->name + ": refused, " + why);
    uint8_t payload[kFaultBytes], frame[64];
    write_fault(Fault{CloseReason::kServerFull, FrameStatus::kOk, 0}, payload);
    const size_t n = write_frame(MessageType::kClose, 0, payload, kFaultBytes, frame, sizeof frame);
    size_t moved = 0;
    (void)c->transport->write(frame, n, &moved);
    c->transport->close();
  };
  if (clients_.size() >= options_.max_clients)
    return refuse(std::to_string(clients_.size()) + " clients already (--max-clients " +
                  std::to_string(options_.max_clients) + ")");
  if (fd >= 0 && !serial) c->address = address_of(name);
  if (options_.per_address > 0 && !c->address.empty()) {
    uint32_t same = 0;
    for (const auto& other : clients_) same += other->address == c->address;
    if (same >= options_.per_address)
      return refuse(std::to_string(same) + " connections from " + c->address + " already (--per-address " +
                    std::to_string(options_.per_address) + ")");
  }
  // No cut state yet: it is made, as large as the cut, at the first update.
  if (!c->sender.init(model_->view(), model_->bounds(), nullptr, 0, &scratch_)) {
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

void Server::begin_session(Client& c) {
  c.hello = c.report.hello = true;
  ++c.report.sessions;
  c.session_from = c.report.updates;
}

void Server::end_session(Client& c) {
  // A serial line stays served: the next hello on it starts a new session.
  c.hello = false;
  c.pending = false;
  c.out.clear();
  c.out_at = 0;
  c.retained.clear();
  c.sender.end();
  c.sender.use_class_bits(nullptr, 0);
  std::vector<uint8_t>().swap(c.state);  // its memory too (assigning {} keeps the capacity)
  std::vector<uint8_t>().swap(c.class_bits);
  c.reader.reset();
}

bool Server::grow_state(Client& c, size_t needed) {
  if (needed <= c.state.size()) return true;
  std::vector<uint8_t> state(needed + needed / 8 + 256);  // an eighth again: a cut that grows slowly costs few refusals
  if (!c.sender.relocate(state.data(), state.size())) return false;
  c.state = std::move(state);
  return true;
}

bool Server::update(Client& c) {
  for (int attempt = 0; attempt < 24; ++attempt) {
    if (c.sender.update(c.camera, options_.cull, Client::sink, &c)) return true;
    if (c.sender.cut_status() != CutStatus::kStorageTooSmall) return false;
    // The cut outgrew the work space (shared: it doubles, at least to what
    // the refused update reached) or the client's sent set (exactly what it
    // needs and an eighth again), and it is made again.
    const uint64_t needed = c.sender.cut().needed_capacity();
    const uint64_t grown = std::max<uint64_t>(needed + needed / 8 + 256, 2 * uint64_t{scratch_.cut.capacity});
    if (needed > scratch_.cut.capacity) {
      scratch_storage_.assign(SenderScratch::bytes(static_cast<uint32_t>(std::min<uint64_t>(grown, 0x7FFFFFFF))) / 8 + 1, 0);
      scratch_.init(scratch_storage_.data(), scratch_storage_.size() * 8);
    }
    if (!grow_state(c, c.sender.cut().needed_state_bytes())) return false;
  }
  return false;
}

void Server::handle(Client& c, const Frame& f) {
  switch (f.type) {
    case MessageType::kHello: {
      // A second hello on a socket: the stream cannot start over mid-byte-stream
      // (and a peer repeating it without reading would grow the queue).
      if (c.hello && !c.serial)
        return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "a second hello on a stream socket");
      if (c.hello && c.serial) {  // a serial client resynchronising, or a new one: the stream starts over
        log(c.name + ": hello again (a new session, or resynchronising), " + std::to_string(c.dropped_packets) +
            " packets dropped so far");
        end_session(c);
      }
      Hello h;
      if (!parse_hello(f.payload, f.payload_bytes, &h))
        return close_client(c, CloseReason::kBadHello, FrameStatus::kBadPayload, f.sequence, "a malformed hello");
      if (h.version < kOldestProtocolVersion || h.version > kProtocolVersion)
        return close_client(c, CloseReason::kUnsupported, FrameStatus::kOk, f.sequence,
                            "protocol version " + std::to_string(h.version));
      if (!options_.token.empty() &&
          !hello_token_matches(h, reinterpret_cast<const uint8_t*>(options_.token.data()), options_.token.size()))
        return close_client(c, CloseReason::kBadToken, FrameStatus::kOk, f.sequence,
                            h.token_bytes == 0 ? "a hello without the token this server needs"
                                               : "a hello with a wrong token");
      c.hello_message = h;
      // Which classes it has been sent (protocol 4): a bit each, from now on.
      c.class_bits.assign(StreamSender::class_bits_bytes(model_->view().header), 0);
      c.sender.use_class_bits(c.class_bits.data(), c.class_bits.size());
      char line[160];
      std::snprintf(line, sizeof line, "%s: hello %ux%u %s, attributes%s%s%s, cache %u nodes%s", c.name.c_str(), h.width,
                    h.height, h.pixel_format ? "rgb888" : "rgb565", h.attributes & kWantNormals ? " normals" : "",
                    h.attributes & kWantColor ? " colour" : "", h.attributes & kWantCoded ? " coded" : "", h.cache_capacity,
                    h.attributes & kResuming ? ", resuming" : "");
      log(line);
      if (h.attributes & kResuming) {  // the startup waits for the resume's parts
        c.resuming = true;
        c.resume_total = 0;
        c.resume_previous = 0xFFFFFFFFu;
        std::vector<uint32_t>().swap(c.held);
        return;
      }
      if (!c.sender.start(h, Client::sink, &c))
        return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "the hello could not be served");
      return begin_session(c);
    }
    case MessageType::kResume: {
      ResumePart part;
      const auto refuse = [&](const std::string& why) {
        std::vector<uint32_t>().swap(c.held);
        c.resuming = false;
        close_client(c, CloseReason::kBadResume, FrameStatus::kBadPayload, f.sequence, why);
      };
      if (!c.resuming) return refuse("a resume without a hello announcing it");
      if (!parse_resume_part(f.payload, f.payload_bytes, &part)) return refuse("a malformed resume");
      const uint32_t nodes = model_->view().header.node_count;
      const uint32_t most = std::min(nodes, c.hello_message.cache_capacity);
      if (c.held.empty() && c.resume_previous == 0xFFFFFFFFu) {  // the first part
        if (part.total > most)
          return refuse("a resume of " + std::to_string(part.total) + " nodes, more than the " + std::to_string(most) +
                        (most == nodes ? " the model has" : " its cache holds"));
        c.resume_tag = part.model_tag;
        c.resume_total = part.total;
        c.held.reserve(part.total);
      } else if (part.model_tag != c.resume_tag || part.total != c.resume_total) {
        return refuse("a resume whose parts disagree on the model or the count");
      }
      const uint8_t* at = part.ids;
      const uint8_t* end = part.ids + part.ids_bytes;
      for (uint32_t id = 0;;) {
        const ResumeId r = next_resume_id(&at, end, &c.resume_previous, &id);
        if (r == ResumeId::kEnd) break;
        if (r == ResumeId::kMalformed) return refuse("a malformed resume (a cut-off or oversized id)");
        if (r == ResumeId::kRepeated)
          return refuse("a resume naming node " + std::to_string(c.resume_previous) + " twice");
        if (id >= nodes)
          return refuse("a resume naming node " + std::to_string(id) + ", beyond the model's " + std::to_string(nodes) +
                        " nodes");
        if (c.held.size() >= c.resume_total)
          return refuse("a resume of more nodes than the " + std::to_string(c.resume_total) + " it announced");
        c.held.push_back(id);
      }
      if (!part.last) return;
      if (c.held.size() != c.resume_total)
        return refuse("a resume of " + std::to_string(c.held.size()) + " nodes where it announced " +
                      std::to_string(c.resume_total));
      c.resuming = false;
      Hello h = c.hello_message;
      const uint32_t tag = c.sender.model_tag(h.attributes);
      bool resumed = false;
      if (tag == c.resume_tag && tag != 0) {
        // It holds this model's nodes: it is sent only what it lacks.
        const auto* held = reinterpret_cast<const NodeId*>(c.held.data());
        const auto count = static_cast<uint32_t>(c.held.size());
        resumed = grow_state(c, sent_set_bytes(held, count)) && c.sender.resume(h, held, count, Client::sink, &c);
      }
      if (resumed) {
        log(c.name + ": resumed with the " + std::to_string(c.held.size()) + " nodes it holds");
      } else {
        log(c.name + ": a resume for another model (or startup): starting over");
        if (!c.sender.start(h, Client::sink, &c))
          return close_client(c, CloseReason::kBadHello, FrameStatus::kOk, f.sequence, "the hello could not be served");
      }
      std::vector<uint32_t>().swap(c.held);
      return begin_session(c);
    }
    case MessageType::kCamera: {
      CameraUpdate u;
      if (!c.hello && c.serial) return;  // left on the line by an earlier session: the next hello starts one
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
      if (c.serial) {  // the line stays: the next hello on it starts a new session
        if (!c.hello) return;  // a stale close left on the line
        const uint32_t n = c.report.updates - c.session_from;
        log(c.name + ": session " + std::to_string(c.report.sessions) + " ended by the client after " + std::to_string(n) +
            (n == 1 ? " update" : " updates"));
        end_session(c);
        c.gone = options_.serial_once;
        return;
      }
      log(c.name + ": closed by the client");
      c.gone = true;
      return;
    default:
      if (c.serial && !c.hello) return;  // garbage before a session: ignored
      return close_client(c, CloseReason::kBadFrame, FrameStatus::kUnknownType, f.sequence,
                          std::string("a ") + message_type_name(static_cast<uint8_t>(f.type)) + " message from a client");
  }
}

void Server::accept_all(Clock::time_point now) {
  if (listen_fd_ < 0 || now < accept_paused_until_) return;
  for (std::string peer;;) {
    int err = 0;
    const int fd = tcp_accept(listen_fd_, &peer, &err);
    if (fd >= 0) {
      add_client(std::make_unique<TcpTransport>(fd, peer), fd, peer);
      continue;
    }
    if (err != EAGAIN && err != EINTR && err != ECONNABORTED) {
      // Out of descriptors (EMFILE, ENFILE) or memory: the pending
      // connection stays queued and the listener stays readable, so the
      // loop would spin. It rests instead, and says so.
      log(std::string("accept failed: ") + std::strerror(err) + " (" + std::to_string(clients_.size()) +
          " clients); not accepting for " + std::to_string(kAcceptPauseMs) + " ms");
      accept_paused_until_ = now + std::chrono::milliseconds(kAcceptPauseMs);
    }
    return;
  }
}

void Server::reopen_line(Client& c, Clock::time_point now) {
  if (now < c.retry) return;
  c.retry = now + std::chrono::milliseconds(kReopenMs);
  int fd = -1;
  std::unique_ptr<Transport> t = c.reopen(&fd);
  if (t == nullptr) return;
  c.transport = std::move(t);
  c.fd = fd;
  c.detached = false;
  c.deframer.init(c.cobs_storage.data(), c.cobs_storage.size());
  c.heard = now;
  log(c.name + ": the line is back");
}

void Server::read_from(Client& c, Clock::time_point now) {
  // In: every whole frame; a fault closes the client with its reason.
  uint8_t buf[4096];
  for (int rounds = 0; rounds < 16 && !c.closing && !c.gone; ++rounds) {
    size_t got = 0;
    const TransportStatus s = c.transport->read(buf, sizeof buf, &got);
    if (s == TransportStatus::kClosed || s == TransportStatus::kError) {
      const std::string why = s == TransportStatus::kError ? std::string(": ") + c.transport->last_error() : "";
      if (c.serial && c.reopen) {
        // The device went away (unplugged): the session ends, and the line is
        // opened again when it comes back.
        log(c.name + ": the line hung up; reopening it when it comes back");
        end_session(c);
        c.transport->close();
        c.fd = -1;
        c.detached = true;
        c.retry = now + std::chrono::milliseconds(kReopenMs);
        return;
      }
      log(c.name + ": disconnected" + why + (c.reader.buffered() > 0 ? " mid-frame" : ""));
      c.gone = true;
      return;
    }
    if (s != TransportStatus::kOk || got == 0) return;
    c.report.bytes_in += got;
    c.heard = now;
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
}

size_t Server::step(int timeout_ms) {
  // Wait for any socket: the listener, readable clients, clients with output.
  std::vector<pollfd> fds;
  bool unpolled = false;
  if (listen_fd_ >= 0 && Clock::now() >= accept_paused_until_) fds.push_back({listen_fd_, POLLIN, 0});
  for (const auto& c : clients_) {
    if (c->detached) continue;
    if (c->fd < 0) unpolled = true;
    else fds.push_back({c->fd, static_cast<short>(POLLIN | (c->idle() ? 0 : POLLOUT)), 0});
  }
  if (!fds.empty()) poll(fds.data(), static_cast<nfds_t>(fds.size()), unpolled ? 0 : timeout_ms);
  else if (timeout_ms > 0 && !unpolled) poll(nullptr, 0, std::min(timeout_ms, kReopenMs));
  const Clock::time_point now = Clock::now();
  accept_all(now);
  const auto ms = [](int n) { return std::chrono::milliseconds(n); };
  for (auto& owned : clients_) {
    Client& c = *owned;
    if (c.detached) {
      reopen_line(c, now);
      if (c.detached) continue;
    }
    read_from(c, now);
    if (c.detached) continue;
    // Timeouts: a socket that never says hello, or says nothing for long
    // (a serial line waits for its next session whatever it hears).
    if (!c.serial && !c.closing && !c.gone) {
      if (!c.hello && options_.hello_timeout_ms > 0 && now - c.opened > ms(options_.hello_timeout_ms))
        close_client(c, CloseReason::kTimeout, FrameStatus::kOk, 0,
                     "no hello within " + std::to_string(options_.hello_timeout_ms) + " ms");
      else if (options_.idle_timeout_ms > 0 && now - c.heard > ms(options_.idle_timeout_ms))
        close_client(c, CloseReason::kTimeout, FrameStatus::kOk, 0,
                     "nothing heard for " + std::to_string(options_.idle_timeout_ms) + " ms");
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
      if (update(c)) {
        if (c.report.updates++ == 0)
          log(c.name + ": first cut " + std::to_string(c.sender.cut().sent_count()) + " nodes, " +
              std::to_string(c.out.size() - before) + " bytes");
        c.report.cut_nodes = c.sender.cut().sent_count();
      } else if (c.sender.cut_status() != CutStatus::kOk) {
        close_client(c, CloseReason::kShutdown, FrameStatus::kOk, 0, "its cut could not be made (out of memory)");
      }
    }
    if (!c.gone && !c.write_out()) {
      log(c.name + ": disconnected while sending");
      c.gone = true;
    }
    if (c.idle() && !c.serial && c.out.capacity() > kQueueKept) {
      // A socket client's queue is let go once written (the first cut's is
      // the largest it will be): what it keeps follows its cut's change.
      std::vector<uint8_t>().swap(c.out);
      c.out_at = 0;
    } else if (c.idle() && c.serial && c.out.size() > kRetainedBytes) {
      // A client that does not acknowledge: the oldest frames go (asked
      // for again, the stream starts over).
      c.release(c.sender.next_sequence());
    }
    if (c.closing && c.idle()) c.gone = true;
    c.report.queued_bytes = c.out.size();
    c.report.state_bytes = c.state_bytes();
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
      ++served_;
    } else {
      ++i;
    }
  }
  return clients_.size();
}

void Server::shutdown(const std::string& why) {
  const size_t connected = clients_.size();
  for (auto& owned : clients_) {
    Client& c = *owned;
    if (c.detached || c.gone) continue;
    if (c.hello && !c.closing) close_client(c, CloseReason::kShutdown, FrameStatus::kOk, 0, "the server is stopping");
    (void)c.write_out();  // a stalled peer is not waited for
    c.transport->close();
  }
  clients_.clear();
  log("stopping (" + why + "): " + std::to_string(connected) + " clients connected, " +
      std::to_string(served_ + connected) + " served since the start");
  if (listen_fd_ >= 0) tcp_close(listen_fd_);
  listen_fd_ = -1;
}

std::vector<ClientReport> Server::report() const {
  std::vector<ClientReport> out;
  for (const auto& c : clients_) out.push_back(c->report);
  return out;
}

}  // namespace stipple
